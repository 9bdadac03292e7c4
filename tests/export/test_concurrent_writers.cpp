// Writers of one configuration take turns: two to four `tunekit export --write` processes
// started at once on one printer.cfg, each changing a setting of its own, never lose an update
// (every writer that exits 0 finds its change in the final file; the others are refused with one
// line); a temporary file left by a writer killed before its rename is removed by the next one.
#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "test_support.hpp"

extern char** environ;

using tunekit::test::read_text;
using tunekit::test::scratch_dir;
namespace fs = std::filesystem;

// The whole file in a namespace of its own: the test areas are unity builds, and other files
// have helpers of the same names.
namespace test_concurrent_writers {

const std::string kConfig =
    "[printer]\nkinematics: cartesian\n\n[extruder]\nstep_pin: PA1\npressure_advance: 0.02\n\n"
    "[input_shaper]\nshaper_type_x: mzv\nshaper_freq_x: 40\nshaper_type_y: mzv\nshaper_freq_y: 40\n";

struct Writer {
  std::vector<std::string> args;  // what it changes
  std::string expect;             // the line its change leaves in the file
};

// Four writers, each changing one setting and leaving the others alone.
const std::vector<Writer> kWriters = {
    {{"--pa-k", "0.031", "--no-shaper"}, "pressure_advance: 0.031"},
    {{"--shaper-x", "ei:61", "--no-pa"}, "shaper_freq_x: 61"},
    {{"--shaper-y", "zv:52", "--no-pa"}, "shaper_freq_y: 52"},
    {{"--pa-smooth", "0.05", "--no-shaper"}, "pressure_advance_smooth_time: 0.05"},
};

pid_t spawn_export(const std::string& cfg, const Writer& w, const std::string& log) {
  std::vector<std::string> argv_s{TUNEKIT_EXE, "export", "-f", "klipper", "-c", cfg, "--write"};
  argv_s.insert(argv_s.end(), w.args.begin(), w.args.end());
  std::vector<char*> argv;
  for (auto& a : argv_s) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&fa, 2, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, argv[0], &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  REQUIRE(rc == 0);
  return pid;
}

TEST_CASE("two to four concurrent export --write on one configuration lose no update (100 trials)",
          "[export][concurrency]") {
  const std::string root = scratch_dir("concurrent_writers");
  std::mt19937 rng(20261129);
  int refused = 0, written = 0, writers = 0;
  for (int trial = 0; trial < 100; ++trial) {
    const std::string dir = root + "/t" + std::to_string(trial);
    fs::create_directories(dir);
    const std::string cfg = dir + "/printer.cfg";
    std::ofstream(cfg) << kConfig;
    const int n = 2 + static_cast<int>(rng() % 3);
    writers += n;
    std::vector<pid_t> pids;
    for (int i = 0; i < n; ++i)
      pids.push_back(spawn_export(cfg, kWriters[static_cast<std::size_t>(i)], dir + "/w" + std::to_string(i)));
    for (pid_t p : pids) {
      int status = 0;
      ::waitpid(p, &status, 0);
    }
    const std::string final_text = read_text(cfg);
    for (int i = 0; i < n; ++i) {
      const std::string log = read_text(dir + "/w" + std::to_string(i));
      INFO("trial " << trial << " writer " << i << ": " << log << "\nfinal:\n" << final_text);
      const bool ok = log.find("tunekit: error:") == std::string::npos;
      if (ok) {
        ++written;
        CHECK(final_text.find(kWriters[static_cast<std::size_t>(i)].expect) != std::string::npos);
      } else {
        ++refused;
        CHECK(log.find("changed since it was read") != std::string::npos);
      }
    }
    // No temporary file is left beside the configuration.
    for (const auto& e : fs::directory_iterator(dir))
      CHECK(e.path().filename().string().find(".tmp.") == std::string::npos);
  }
  CHECK(written >= 100);  // at least one writer per trial got through
  WARN(writers << " writers in 100 trials: " << written << " wrote their change, " << refused
               << " were refused, none lost");
}

TEST_CASE("a temporary file a killed writer left beside the configuration is removed by the next export", "[export]") {
  const std::string dir = scratch_dir("stale_temporary");
  const std::string cfg = dir + "/e.cfg";
  std::ofstream(cfg) << kConfig;
  const std::string stale = dir + "/.e.cfg.tmp.Ab12Cd";
  std::ofstream(stale) << "half a configuration";
  const std::string other = dir + "/.e.cfg.tmp.notmine.txt";  // not a name mkstemp gives
  std::ofstream(other) << "x";
  const auto r = tunekit::test::run_cli({"export", "-f", "klipper", "-c", cfg, "--pa-k", "0.03", "--write"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK_FALSE(fs::exists(stale));
  CHECK(fs::exists(other));
  CHECK(r.err.find(".e.cfg.tmp.Ab12Cd") != std::string::npos);
}

}  // namespace test_concurrent_writers
