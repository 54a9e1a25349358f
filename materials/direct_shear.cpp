// Placeholder until the direct shear test lands (being written now); replaced by the real test.
#include "direct_shear.h"

#include <stdexcept>

namespace dem::materials {

SimulatedOutcome run_direct_shear(const MaterialModel&, const TestSetup& setup, const TestOptions&) {
  throw CaseError(setup.location.str() + ": direct_shear: not available in this build yet");
}

}  // namespace dem::materials
