#pragma once
// Large buffers that are written once from end to end (a parsed file's columns): every 4 KiB page
// of fresh memory costs the kernel one page fault when it is first written, about 5,000 of them
// for a 410,000-row accelerometer file, a third of a whole `tunekit shaper` process. Where 2 MiB
// transparent huge pages back such a buffer, it takes one fault per 2 MiB instead.

#include <cstddef>

namespace tunekit::core {

/// Advises the kernel (Linux madvise, MADV_HUGEPAGE) to back the whole 2 MiB pages inside
/// [data, data + bytes) with transparent huge pages when they are first written. Advice only: it
/// changes no byte and no result, and does nothing for smaller buffers, on kernels without
/// transparent huge pages or where they are switched off ("never").
void advise_huge_pages(void* data, std::size_t bytes);

}  // namespace tunekit::core
