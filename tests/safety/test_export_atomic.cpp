// export changes configuration all or nothing: every file it writes (configuration, backup,
// G-code, JSON) is computed first, and when any of them cannot be written no file changes.
// Input text is bytes: a Latin-1 comment survives, and the JSON report carries it as valid UTF-8.
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "test_support.hpp"
#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/core/atomic_file.hpp"

using tunekit::test::read_text;
using tunekit::test::run_cli;
using tunekit::test::scratch_dir;
namespace fs = std::filesystem;

namespace {

const std::string kLatin1Config =
    "[printer]\nkinematics: cartesian\n\n"
    "[extruder]\n# caf\xe9 comment: Latin-1, not UTF-8\nstep_pin: PA1\npressure_advance: 0.02\n";

/// Every regular file under `dir` with its bytes.
std::map<std::string, std::string> snapshot(const std::string& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) files[e.path().string()] = read_text(e.path().string());
  return files;
}

/// Runs the tunekit executable without root's privilege to write anywhere (as user nobody
/// when the tests run as root), so that a directory without write permission refuses writes.
tunekit::test::CliRun run_unprivileged(const std::string& args) {
  const std::string prefix = ::geteuid() == 0 ? "setpriv --reuid=65534 --regid=65534 --clear-groups " : "";
  const std::string err_path = scratch_dir("export_atomic_stderr") + "/stderr";
  const std::string cmd = prefix + TUNEKIT_EXE + std::string(" ") + args + " 2>" + err_path;
  tunekit::test::CliRun r;
  FILE* p = ::popen(cmd.c_str(), "r");
  REQUIRE(p);
  std::array<char, 4096> buf{};
  std::size_t n;
  while ((n = std::fread(buf.data(), 1, buf.size(), p)) > 0) r.out.append(buf.data(), n);
  const int status = ::pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.err = read_text(err_path);
  return r;
}

std::string fixture(const std::string& name) { return tunekit::test::dataset("../tests/export/fixtures/" + name); }

}  // namespace

TEST_CASE("export keeps a Latin-1 comment byte for byte and reports valid UTF-8 JSON", "[safety]") {
  const auto dir = scratch_dir("export_latin1");
  const std::string cfg = dir + "/printer.cfg";
  std::ofstream(cfg, std::ios::binary) << kLatin1Config;
  // Preview: exit 0, JSON parses, the comment is carried as U+00E9.
  const auto preview = run_cli({"export", "-f", "klipper", "-c", cfg, "--pa-k", "0.05", "--json"});
  INFO(preview.err);
  REQUIRE(preview.code == 0);
  const auto j = nlohmann::json::parse(preview.out);
  CHECK(j["results"]["export"].dump().find("\\u00e9") == std::string::npos);  // dump() keeps UTF-8 as is
  CHECK(preview.out.find("caf\xc3\xa9") != std::string::npos);
  CHECK(read_text(cfg) == kLatin1Config);
  // Write: the comment's byte survives unchanged, the value changes.
  const auto w = run_cli({"export", "-f", "klipper", "-c", cfg, "--pa-k", "0.05", "--write", "-o", dir + "/r.json"});
  INFO(w.err);
  REQUIRE(w.code == 0);
  const std::string after = read_text(cfg);
  CHECK(after.find("\n# caf\xe9 comment") != std::string::npos);
  CHECK(after.find("pressure_advance: 0.05") != std::string::npos);
  CHECK_NOTHROW(nlohmann::json::parse(read_text(dir + "/r.json")));
  CHECK(tunekit::calibration::utf8_or_latin1("caf\xe9") == "caf\xc3\xa9");
  CHECK(tunekit::calibration::utf8_or_latin1("caf\xc3\xa9") == "caf\xc3\xa9");
  CHECK(tunekit::calibration::utf8_or_latin1("\xed\xa0\x80") ==
        "\xc3\xad\xc2\xa0\xc2\x80");  // a surrogate is not UTF-8
}

TEST_CASE("fault: export --write with any output path unwritable leaves every file byte-identical", "[safety]") {
  // Writable directories are writable for everyone: the command runs as user nobody when the
  // tests run as root, and only the one directory of each case may refuse it. Every file lives
  // under the system's temporary directory, where user nobody can reach it: a clone (and its
  // build directory) under /root, mode 0700 on Debian, is out of its reach, and the fault cases
  // must fail for their own reason.
  const std::string root =
      (fs::temp_directory_path() / ("tunekit-export-fault-" + std::to_string(::getpid()))).string();
  fs::remove_all(root);
  fs::create_directories(root);
  ::chmod(root.c_str(), 0777);
  const std::string results = root + "/shaper_zv.json";
  fs::copy_file(fixture("shaper_zv.json"), results, fs::copy_options::overwrite_existing);
  ::chmod(results.c_str(), 0644);
  struct Case {
    std::string name;
    std::string extra;   // arguments naming the unwritable output
    std::string locked;  // directory made read-only ("" for none)
  };
  const std::vector<Case> cases{
      {"configuration directory read-only", "--gcode {root}/locked/x.gcode -o {root}/locked/r.json", "cfgdir"},
      {"--gcode in a read-only directory", "--gcode {root}/locked/x.gcode", "locked"},
      {"-o in a read-only directory", "-o {root}/locked/r.json", "locked"},
      {"--gcode in a missing directory", "--gcode /nonexistent/x.gcode", ""},
      {"-o in a missing directory", "-o /nonexistent/r.json", ""},
      {"--gcode names a directory", "--gcode {root}/adir", ""},
      {"-o names a directory", "-o {root}/adir", ""},
  };
  for (const auto& c : cases) {
    INFO(c.name);
    fs::remove_all(root + "/cfgdir");
    fs::remove_all(root + "/locked");
    fs::create_directories(root + "/cfgdir");
    fs::create_directories(root + "/locked");
    fs::create_directories(root + "/adir");
    const std::string cfg = root + "/cfgdir/printer.cfg";
    std::ofstream(cfg, std::ios::binary) << kLatin1Config;
    std::ofstream(root + "/locked/x.gcode", std::ios::binary) << "; an older G-code file\n";
    ::chmod(cfg.c_str(), 0644);
    ::chmod((root + "/locked/x.gcode").c_str(), 0644);
    for (const char* d : {"/cfgdir", "/locked", "/adir"}) ::chmod((root + d).c_str(), 0777);
    if (!c.locked.empty()) ::chmod((root + "/" + c.locked).c_str(), 0555);
    const auto before = snapshot(root);
    std::string extra = c.extra;
    for (auto at = extra.find("{root}"); at != std::string::npos; at = extra.find("{root}")) extra.replace(at, 6, root);
    const auto r = run_unprivileged("export -f klipper -c " + cfg + " --pa-k 0.05 " + results + " --write " + extra);
    for (const char* d : {"/cfgdir", "/locked"}) ::chmod((root + d).c_str(), 0777);
    INFO(r.err);
    CHECK(r.code == 2);
    CHECK(r.err.rfind("tunekit: error: ", 0) == 0);
    CHECK(snapshot(root) == before);  // byte-identical, no backup, no temporary file left
  }
  // The same command with every path writable changes them all (the fault cases were real).
  const std::string cfg = root + "/cfgdir/printer.cfg";
  const auto ok = run_unprivileged("export -f klipper -c " + cfg + " --pa-k 0.05 " + results + " --write --gcode " +
                                   root + "/locked/x.gcode -o " + root + "/locked/r.json");
  INFO(ok.err);
  CHECK(ok.code == 0);
  CHECK(read_text(cfg).find("pressure_advance: 0.05") != std::string::npos);
  CHECK(read_text(root + "/locked/x.gcode").find("SET_PRESSURE_ADVANCE") != std::string::npos);
  CHECK(fs::exists(root + "/locked/r.json"));
  fs::remove_all(root);
}

TEST_CASE("a file batch that fails on a later rename puts back the files it already replaced", "[safety]") {
  const auto dir = scratch_dir("file_batch_rollback");
  std::ofstream(dir + "/a", std::ios::binary) << "old a";
  tunekit::core::FileBatch b;
  b.add(dir + "/a", "new a");
  b.add(dir + "/new", "new file");
  b.add(dir + "/c", "new c");
  CHECK_THROWS_AS(b.commit([&](const std::string& target) {
    if (target == dir + "/c") throw std::runtime_error("simulated failure");
  }),
                  tunekit::InputError);
  CHECK(read_text(dir + "/a") == "old a");
  CHECK_FALSE(fs::exists(dir + "/new"));
  CHECK_FALSE(fs::exists(dir + "/c"));
  std::size_t files = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++files;
  CHECK(files == 1);  // no temporary file left
  b.commit();
  CHECK(read_text(dir + "/a") == "new a");
  CHECK(read_text(dir + "/c") == "new c");
}

TEST_CASE("export refuses non-finite and absurd values before writing anything", "[safety]") {
  const auto dir = scratch_dir("export_absurd");
  const std::string cfg = dir + "/printer.cfg";
  std::ofstream(cfg, std::ios::binary) << kLatin1Config;
  for (const std::vector<std::string>& extra :
       std::vector<std::vector<std::string>>{{"--pa-k", "1e308"},
                                             {"--pa-k", "nan"},
                                             {"--pa-k", "inf"},
                                             {"--pa-k", "-0.1"},
                                             {"--shaper-x", "zv:1e-300"},
                                             {"--shaper-x", "zv:nan"},
                                             {"--shaper-x", "mzv:45:inf"},
                                             {"--pa-k", "0.05", "--pa-smooth", "nan"},
                                             {"--pa-k", "0.05", "--design-flow", "inf"}}) {
    std::vector<std::string> args{"export", "-f", "klipper", "-c", cfg, "--write"};
    args.insert(args.end(), extra.begin(), extra.end());
    const auto r = run_cli(args);
    INFO(extra[0] << " " << extra[1] << ": " << r.err);
    CHECK(r.code == 2);
    CHECK(r.err.find("nothing to export") == std::string::npos);
  }
  CHECK(read_text(cfg) == kLatin1Config);
  std::size_t files = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++files;
  CHECK(files == 1);
}
