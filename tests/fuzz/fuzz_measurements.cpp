// libFuzzer target: the measurement-file reader (dem::materials::parse_measurements).
#include <cstddef>
#include <cstdint>
#include <string>

#include "bad_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size > 64 * 1024) return 0;
  dem::fuzz::read_measurement_text(std::string(reinterpret_cast<const char*>(data), size));
  return 0;
}
