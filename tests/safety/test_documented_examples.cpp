// The examples a user copies: every shell example of the README and every example of a command's
// --help that reads only the repository's own files runs, in a scratch directory, and exits 0.
// (Examples that need a printer's own files, a device, or the simulated printer are run by the
// tests of their commands.)
#include <filesystem>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "test_support.hpp"

using tunekit::test::run_cli;
using tunekit::test::shell_words;
namespace fs = std::filesystem;

namespace {

/// The commands in `text` that start with `prefix` ("build/apps/tunekit " in the README, "tunekit "
/// in a --help), continuation lines joined and trailing comments removed. `in_blocks`: only lines
/// inside ```sh blocks count.
std::vector<std::string> examples_in(const std::string& text, const std::string& prefix, bool in_blocks) {
  std::vector<std::string> out;
  std::istringstream in(text);
  std::string line, cmd;
  bool in_sh = !in_blocks;
  while (std::getline(in, line)) {
    if (in_blocks && line.rfind("```", 0) == 0) {
      in_sh = !in_sh && line.find("sh") != std::string::npos;
      continue;
    }
    if (!in_sh) continue;
    if (const auto hash = line.find("  #"); hash != std::string::npos) line.resize(hash);
    while (!line.empty() && line.back() == ' ') line.pop_back();
    const bool continued = !line.empty() && line.back() == '\\';
    if (continued) line.pop_back();
    if (cmd.empty()) {
      const auto at = line.find(prefix);
      if (at == std::string::npos || line.find_first_not_of(' ') != at) continue;
      line = line.substr(at + prefix.size());
    }
    cmd += line + " ";
    if (continued) continue;
    out.push_back(cmd);
    cmd.clear();
  }
  return out;
}

/// Options whose value is a file the command writes (it need not exist).
const std::set<std::string> kOutputOptions{"-o",         "--json-file", "--gcode",       "--gcode-out", "--out",
                                           "--run-dir",  "--plot",      "--export-file", "--orca-out",  "--overlay",
                                           "--plot-out", "--csv-out",   "--profile-out", "--report"};

/// The example's words with datasets/ made absolute; empty when it needs a file the repository
/// does not have, a device, or a machine.
std::vector<std::string> runnable_words(const std::string& example, const std::string& root) {
  std::vector<std::string> words;
  const auto all = shell_words(example);
  // The history's reports need the user's own database of records.
  if (all.empty() || all[0] == "history") return {};
  for (std::size_t i = 0; i < all.size(); ++i) {
    std::string w = all[i];
    if (w == ">" || w == "|") return {};  // a shell pipeline: not a single command
    if (w == "--machine" || w == "--port" || w == "--camera-device" || w.rfind("/dev/", 0) == 0) return {};
    const bool output = i > 0 && kOutputOptions.count(all[i - 1]) > 0;
    if (w.rfind("datasets/", 0) == 0) w = root + "/" + w;
    const bool looks_like_file = w.find('/') != std::string::npos || w.find(".csv") != std::string::npos ||
                                 w.find(".json") != std::string::npos || w.find(".cfg") != std::string::npos ||
                                 w.find(".toml") != std::string::npos || w.find(".gcode") != std::string::npos ||
                                 w.find(".png") != std::string::npos || w.find(".jpg") != std::string::npos ||
                                 w.find(".g") + 2 == w.size() || w.find(".h") + 2 == w.size();
    if (!output && w.rfind("-", 0) != 0 && looks_like_file && !fs::exists(w)) return {};
    words.push_back(w);
  }
  return words;
}

struct Tally {
  std::size_t ran = 0;
  std::vector<std::string> failed;
};

void run_examples(const std::vector<std::string>& examples, const std::string& root, const std::string& scratch,
                  Tally& tally) {
  const auto old_cwd = fs::current_path();
  for (const auto& ex : examples) {
    const auto words = runnable_words(ex, root);
    if (words.empty()) continue;
    fs::current_path(scratch);  // whatever an example writes lands in the scratch directory
    const auto r = run_cli(words);
    fs::current_path(old_cwd);
    ++tally.ran;
    if (r.code != 0) tally.failed.push_back(ex + "-> exit " + std::to_string(r.code) + ": " + r.err);
  }
}

}  // namespace

TEST_CASE("every README example that reads only the repository's files runs and exits 0", "[safety]") {
  const std::string root = fs::path(tunekit::test::dataset("")).parent_path().parent_path().string();
  const auto examples = examples_in(tunekit::test::read_text(root + "/README.md"), "build/apps/tunekit ", true);
  REQUIRE(examples.size() >= 20);
  Tally tally;
  run_examples(examples, root, tunekit::test::scratch_dir("readme_examples"), tally);
  INFO(tally.failed.size() << " failed:\n"
                           << [&] {
                                std::string all;
                                for (const auto& f : tally.failed) all += f + "\n";
                                return all;
                              }());
  CHECK(tally.failed.empty());
  CHECK(tally.ran >= 10);
}

TEST_CASE("every --help example that reads only the repository's files runs and exits 0", "[safety]") {
  const std::string root = fs::path(tunekit::test::dataset("")).parent_path().parent_path().string();
  const auto commands = {"step",  "freq",    "rheo",   "nozzle",  "resonance", "shaper",
                         "belts", "export",  "report", "inspect", "linewidth", "batch",
                         "delta", "history", "run",    "ports",   "overshoot"};
  std::vector<std::string> examples;
  for (const char* c : commands) {
    const auto help = run_cli({c, "--help"});
    for (const auto& e : examples_in(help.out, "tunekit ", false)) examples.push_back(e);
  }
  REQUIRE(examples.size() >= 15);
  Tally tally;
  run_examples(examples, root, tunekit::test::scratch_dir("help_examples"), tally);
  INFO(tally.failed.size() << " failed:\n"
                           << [&] {
                                std::string all;
                                for (const auto& f : tally.failed) all += f + "\n";
                                return all;
                              }());
  CHECK(tally.failed.empty());
  CHECK(tally.ran >= 5);
}
