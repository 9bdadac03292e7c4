// tunekit: the command-line entry point. Everything happens in tunekit::cli::run_cli.
#include <iostream>
#include <string>
#include <vector>

#include "tunekit/cli/commands.hpp"

int main(int argc, char** argv) {
  std::ios::sync_with_stdio(false);
  std::vector<std::string> args(argv + 1, argv + argc);
  return tunekit::cli::run_cli(args, std::cout, std::cerr);
}
