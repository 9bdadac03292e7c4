// Configuration files as they are found on a printer's host: owned by the firmware's user,
// reached through a symbolic link, sharing hard links, or not a regular file or not
// ASCII-compatible text. An edit keeps owner, group and mode, writes a link's target, and
// refuses what it cannot edit safely before a byte is read or written.
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <catch2/catch.hpp>

#include "test_support.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/core/file_bytes.hpp"

using tunekit::test::read_text;
using tunekit::test::run_cli;
using tunekit::test::scratch_dir;
namespace fs = std::filesystem;

namespace {

const std::string kKlipperConfig =
    "[printer]\nkinematics: cartesian\n\n[extruder]\nstep_pin: PA1\npressure_advance: 0.02\n";

void write(const std::string& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

struct stat stat_of(const std::string& path) {
  struct stat st {};
  REQUIRE(::stat(path.c_str(), &st) == 0);
  return st;
}

/// The tunekit executable with `args` under a 20 s limit (a read that blocks on a FIFO or never
/// ends on /dev/zero must fail the test, not hang it); exit code (124: timed out) and stderr.
tunekit::test::CliRun run_limited(const std::string& args, const std::string& scratch) {
  const std::string err = scratch + "/stderr";
  const std::string cmd = "timeout -s KILL 20 " + std::string(TUNEKIT_EXE) + " " + args + " >/dev/null 2>" + err;
  const int status = std::system(cmd.c_str());
  tunekit::test::CliRun r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.err = read_text(err);
  return r;
}

/// Backups export left beside `cfg` (printer.cfg.<stamp>.bak).
int backups_beside(const std::string& cfg) {
  int n = 0;
  const std::string stem = fs::path(cfg).filename().string() + ".";
  for (const auto& e : fs::directory_iterator(fs::path(cfg).parent_path()))
    if (e.path().filename().string().rfind(stem, 0) == 0 && e.path().extension() == ".bak") ++n;
  return n;
}

}  // namespace

TEST_CASE("an edited configuration keeps its owner, group and mode, and so does its backup", "[safety][config]") {
  const std::string dir = scratch_dir("config_owner");
  const std::string cfg = dir + "/printer.cfg";
  write(cfg, kKlipperConfig);
  // As root (CI), the file belongs to another user, as Klipper's printer.cfg belongs to its user.
  const bool root = ::geteuid() == 0;
  const uid_t uid = root ? 4321 : ::geteuid();
  const gid_t gid = root ? 4322 : ::getegid();
  if (root) REQUIRE(::chown(cfg.c_str(), uid, gid) == 0);
  REQUIRE(::chmod(cfg.c_str(), 0640) == 0);
  const auto r = run_cli({"export", "-f", "klipper", "-c", cfg, "--pa-k", "0.05", "--write"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(read_text(cfg).find("pressure_advance: 0.05") != std::string::npos);
  const auto st = stat_of(cfg);
  CHECK(st.st_uid == uid);
  CHECK(st.st_gid == gid);
  CHECK((st.st_mode & 07777) == 0640);
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().extension() == ".bak") {
      const auto b = stat_of(e.path().string());
      CHECK(b.st_uid == uid);
      CHECK(b.st_gid == gid);
      CHECK((b.st_mode & 07777) == 0640);
    }
  CHECK(backups_beside(cfg) == 1);
}

TEST_CASE("an edit through a symbolic link writes the link's target and keeps the link", "[safety][config]") {
  const std::string dir = scratch_dir("config_symlink");
  fs::create_directories(dir + "/real");
  write(dir + "/real/printer.cfg", kKlipperConfig);
  const std::string link = dir + "/printer.cfg";
  fs::create_symlink("real/printer.cfg", link);  // relative, as ln -s makes it
  const auto r = run_cli({"export", "-f", "klipper", "-c", link, "--pa-k", "0.05", "--write"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(fs::is_symlink(link));
  CHECK(fs::read_symlink(link) == "real/printer.cfg");
  CHECK(read_text(dir + "/real/printer.cfg").find("pressure_advance: 0.05") != std::string::npos);
  // Nothing else in the target's directory but the file itself (no temporary file left).
  int files = 0;
  for (const auto& e : fs::directory_iterator(dir + "/real")) files += e.is_regular_file() ? 1 : 0;
  CHECK(files == 1);
}

TEST_CASE("a configuration with several hard links is refused, and no name changes", "[safety][config]") {
  const std::string dir = scratch_dir("config_hardlink");
  const std::string cfg = dir + "/printer.cfg";
  write(cfg, kKlipperConfig);
  fs::create_hard_link(cfg, dir + "/printer-copy.cfg");
  const auto r = run_cli({"export", "-f", "klipper", "-c", cfg, "--pa-k", "0.05", "--write"});
  CHECK(r.code == 2);
  CHECK(r.err.rfind("tunekit: error: ", 0) == 0);
  CHECK(r.err.find("hard links") != std::string::npos);
  CHECK(read_text(cfg) == kKlipperConfig);
  CHECK(read_text(dir + "/printer-copy.cfg") == kKlipperConfig);
  CHECK(fs::hard_link_count(cfg) == 2);
  CHECK(backups_beside(cfg) == 0);
}

TEST_CASE("a FIFO, /dev/zero or a directory as a configuration or input is refused before reading",
          "[safety][config]") {
  const std::string dir = scratch_dir("config_not_regular");
  const std::string fifo = dir + "/printer.cfg";
  REQUIRE(::mkfifo(fifo.c_str(), 0644) == 0);
  fs::create_directories(dir + "/adir");
  write(dir + "/ok.cfg", kKlipperConfig);
  struct Case {
    std::string args, says;
  };
  const std::vector<Case> cases{
      {"export -f klipper --pa-k 0.05 -c " + fifo, "a FIFO"},
      {"export -f klipper --pa-k 0.05 -c /dev/zero", "a character device"},
      {"export -f klipper --pa-k 0.05 -c " + dir + "/adir", "a directory"},
      {"export -f marlin --pa-k 0.05 -c " + fifo, "a FIFO"},
      {"export -f klipper --pa-k 0.05 -c " + dir + "/ok.cfg --gcode-in " + fifo + " --gcode-out " + dir + "/o.gcode",
       "a FIFO"},
      {"step " + fifo + " --time time --input feed --output force", "a FIFO"},
      {"resonance " + fifo, "a FIFO"},
      {"run axis-sweep --dry-run --machine " + fifo, "a FIFO"},
  };
  for (const auto& c : cases) {
    INFO(c.args);
    const auto r = run_limited(c.args, dir);
    INFO(r.err);
    CHECK(r.code == 2);
    CHECK(r.err.rfind("tunekit: error: ", 0) == 0);
    CHECK(r.err.find(c.says) != std::string::npos);
    CHECK(r.err.find("not a regular file") != std::string::npos);
  }
}

TEST_CASE("the shared reader bounds the size of every file it reads", "[safety][config]") {
  const std::string dir = scratch_dir("reader_bound");
  const std::string f = dir + "/big.csv";
  write(f, std::string(1000, 'x'));
  CHECK(tunekit::read_file_bytes(f, 1000).size() == 1000);
  CHECK_THROWS_AS(tunekit::read_file_bytes(f, 999), tunekit::InputError);
  try {
    tunekit::read_file_bytes(f, 999);
  } catch (const tunekit::InputError& e) {
    CHECK(std::string(e.what()).find("larger than 999 bytes") != std::string::npos);
  }
  CHECK(tunekit::read_file_head(f, 10) == std::string(10, 'x'));
  CHECK_THROWS_AS(tunekit::read_file_head("/dev/zero", 10), tunekit::InputError);
}

TEST_CASE("a UTF-16 or UTF-32 configuration is refused, not edited by appending ASCII", "[safety][config]") {
  const std::string dir = scratch_dir("config_utf16");
  // UTF-16LE with and without its byte-order mark, UTF-16BE, UTF-32LE: each ASCII character
  // of the text becomes two or four bytes.
  auto widen = [](const std::string& ascii, int width, bool big_endian) {
    std::string out;
    for (char c : ascii) {
      std::string unit(static_cast<std::size_t>(width), '\0');
      unit[big_endian ? width - 1 : 0] = c;
      out += unit;
    }
    return out;
  };
  const std::string rrf = "; config.g\nM572 D0 S0.02\nM593 P\"zvd\" F40\n";
  struct Case {
    std::string name, firmware, text, says;
  };
  const std::vector<Case> cases{
      {"klipper UTF-16LE with BOM", "klipper", std::string("\xFF\xFE", 2) + widen(kKlipperConfig, 2, false), "UTF-16"},
      {"klipper UTF-16LE without BOM", "klipper", widen(kKlipperConfig, 2, false), "NUL byte"},
      {"rrf UTF-16BE with BOM", "rrf", std::string("\xFE\xFF", 2) + widen(rrf, 2, true), "UTF-16"},
      {"rrf UTF-32LE with BOM", "rrf", std::string("\xFF\xFE\0\0", 4) + widen(rrf, 4, false), "UTF-32"},
  };
  for (const auto& c : cases) {
    INFO(c.name);
    const std::string cfg = dir + "/" + c.firmware + ".cfg";
    write(cfg, c.text);
    const auto r = run_cli({"export", "-f", c.firmware, "-c", cfg, "--pa-k", "0.05", "--write"});
    INFO(r.err);
    CHECK(r.code == 2);
    CHECK(r.err.rfind("tunekit: error: ", 0) == 0);
    CHECK(r.err.find(c.says) != std::string::npos);
    CHECK(r.err.find("ASCII") != std::string::npos);
    CHECK(read_text(cfg) == c.text);
    CHECK(backups_beside(cfg) == 0);
  }
  // UTF-8 with its byte-order mark stays editable.
  const std::string utf8 = dir + "/utf8.cfg";
  write(utf8, "\xEF\xBB\xBF" + kKlipperConfig);
  const auto ok = run_cli({"export", "-f", "klipper", "-c", utf8, "--pa-k", "0.05", "--write"});
  INFO(ok.err);
  CHECK(ok.code == 0);
  CHECK(read_text(utf8).find("pressure_advance: 0.05") != std::string::npos);
}
