// libFuzzer target: the case reader. Text -> parse_case_text -> expand_equipment -> compile (inline
// meshes only; a `file:` mesh must fail with a CaseError) -> initial_state when the case is small.
// Anything but a CaseError (or a clean return) is a finding: crashes, sanitizer reports, hangs
// (libFuzzer -timeout) and allocations beyond -rss_limit_mb.
#include <cstddef>
#include <cstdint>
#include <string>

#include "bad_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size > 64 * 1024) return 0;
  dem::fuzz::read_case_text(std::string(reinterpret_cast<const char*>(data), size));
  return 0;
}
