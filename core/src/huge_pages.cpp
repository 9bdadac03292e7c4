#include "tunekit/core/huge_pages.hpp"

#include <cstdint>

#include <sys/mman.h>

namespace tunekit::core {

namespace {

// The size of a transparent huge page on x86-64 (and on arm64 with 4 KiB pages).
constexpr std::uintptr_t kHugePageBytes = std::uintptr_t{2} << 20;

}  // namespace

void advise_huge_pages(void* data, std::size_t bytes) {
#ifdef MADV_HUGEPAGE
  const auto begin = reinterpret_cast<std::uintptr_t>(data);
  const std::uintptr_t first = (begin + kHugePageBytes - 1) & ~(kHugePageBytes - 1);
  const std::uintptr_t last = (begin + bytes) & ~(kHugePageBytes - 1);
  if (data == nullptr || last <= first) return;
  (void)::madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE);  // refused: nothing changes
#else
  (void)data;
  (void)bytes;
#endif
}

}  // namespace tunekit::core
