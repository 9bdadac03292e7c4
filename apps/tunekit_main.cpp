// tunekit: the command-line entry point. Everything happens in tunekit::cli::run_cli.
#include <iostream>
#include <string>
#include <vector>

#include "tunekit/cli/run_cli.hpp"
#include "tunekit/core/heap_policy.hpp"

int main(int argc, char** argv) {
  tunekit::core::keep_freed_memory_in_heap();
  std::ios::sync_with_stdio(false);
  std::vector<std::string> args(argv + 1, argv + argc);
  return tunekit::cli::run_cli(args, std::cout, std::cerr);
}
