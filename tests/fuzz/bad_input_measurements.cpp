#include "bad_input.h"
#include "measurements.h"

namespace dem::fuzz {

std::string read_measurement_text(const std::string& text) {
  try {
    materials::parse_measurements(text, "fuzz_measurements.yaml");
  } catch (const CaseError& e) {
    return e.what();
  }
  return "";
}

}  // namespace dem::fuzz
