#pragma once
// The heap policy of a tunekit process. The analyses allocate and free buffers of a few MB each
// (a record's columns, spectra, a fit's schedule and residuals). By default glibc maps each block
// above 128 kB (later above the size of the largest freed one) afresh and returns it to the kernel
// when freed, so every new buffer is faulted in page by page again: about a quarter of the time
// the output-error axis fit adds to `tunekit resonance`. A process that runs for a fraction of a
// second does better keeping freed memory in its heap for the next buffer.

namespace tunekit::core {

/// Keeps freed memory in the process's heap: blocks up to 32 MiB (the most glibc allows here)
/// come from the heap, and the heap is not trimmed below 1 GiB. Called first thing by the
/// `tunekit` executable, and by the benchmark programs that time what it runs; not by a library
/// loaded into another program (the Python module), whose heap is that program's.
void keep_freed_memory_in_heap();

}  // namespace tunekit::core
