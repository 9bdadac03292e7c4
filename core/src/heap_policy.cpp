#include "tunekit/core/heap_policy.hpp"

#include <malloc.h>

namespace tunekit::core {

namespace {

// glibc's largest M_MMAP_THRESHOLD (HEAP_MAX_SIZE / 2 on 64-bit), and a trim threshold far above
// what one analysis holds.
constexpr int kMmapThresholdBytes = 32 << 20;
constexpr int kTrimThresholdBytes = 1 << 30;

}  // namespace

void keep_freed_memory_in_heap() {
  mallopt(M_MMAP_THRESHOLD, kMmapThresholdBytes);
  mallopt(M_TRIM_THRESHOLD, kTrimThresholdBytes);
}

}  // namespace tunekit::core
