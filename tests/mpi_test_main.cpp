// main() of the test programs run under `mpirun -np N`: every rank runs every test (the
// collectives need them all) and prints its results; a failure on any rank fails the run.
#include <gtest/gtest.h>

#include <string>

#include "campaign/mpi_campaign.h"

int main(int argc, char** argv) {
  dem::app::mpi::Session session(&argc, &argv);
  ::testing::InitGoogleTest(&argc, argv);
  const int failed = RUN_ALL_TESTS();
  int any = 0;
  for (const std::string& bytes : dem::app::mpi::all_gather(std::to_string(failed))) any = any || std::stoi(bytes) != 0;
  return any;
}
