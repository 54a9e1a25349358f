// Peak resident memory of the benchmark process (Linux /proc), shared by the benchmark programs.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

namespace bench {

/// VmHWM in bytes (0 when unknown).
inline std::size_t peak_rss_bytes() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("VmHWM:", 0) == 0) return static_cast<std::size_t>(std::strtoull(line.c_str() + 6, nullptr, 10)) * 1024;
  return 0;
}

/// Resets VmHWM to the current RSS (Linux: write "5" to /proc/self/clear_refs).
inline bool reset_peak_rss() {
  std::FILE* f = std::fopen("/proc/self/clear_refs", "w");
  if (!f) return false;
  const bool ok = std::fputs("5", f) >= 0;
  return (std::fclose(f) == 0) && ok;
}

}  // namespace bench
