// tunekit: the command-line entry point. Everything happens in tunekit::cli::run_cli.
#include <malloc.h>

#include <iostream>
#include <string>
#include <vector>

#include "tunekit/cli/run_cli.hpp"

int main(int argc, char** argv) {
  // The analyses allocate and free buffers of a few MB each (a record's columns, spectra, a fit's
  // schedule and residuals). By default glibc maps each block above 128 kB (later above the size of
  // the largest freed one) afresh and returns it to the kernel when freed, so every new buffer is
  // faulted in page by page again, about a quarter of the time the output-error axis fit adds to
  // `tunekit resonance`. A process that runs for a fraction of a second does better keeping freed
  // memory in its heap for the next buffer: blocks up to 32 MiB (the most glibc allows here) come
  // from the heap, and the heap is not trimmed below 1 GiB.
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
  std::ios::sync_with_stdio(false);
  std::vector<std::string> args(argv + 1, argv + argc);
  return tunekit::cli::run_cli(args, std::cout, std::cerr);
}
