#include "base/allocator.h"

#include <cstdlib>  // defines __GLIBC__ where the C library is glibc

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace dem {

bool tune_allocator() {
#if defined(__GLIBC__)
  constexpr int kMmapThreshold = 256 * 1024;  // [bytes]; glibc's initial value, kept fixed
  return mallopt(M_MMAP_THRESHOLD, kMmapThreshold) == 1;
#else
  return false;
#endif
}

}  // namespace dem
