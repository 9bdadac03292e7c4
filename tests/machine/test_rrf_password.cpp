// RepRapFirmware's web server with a password (M551), against the simulated board, which keeps
// sessions as RepRapFirmware's src/Networking/HttpResponder.cpp does (GetJsonResponse "connect":
// {"err":1} wrong password, {"err":2} no session free, {"err":0,...,"sessionKey":n}; every other
// request "401 Not authorized" without a session; X-Session-Key; rr_disconnect).
#include <catch2/catch.hpp>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "test_support.hpp"
#include "tunekit/calibration/analyses/simulated_machine.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/machine/machine_profile.hpp"
#include "tunekit/machine/rrf_http.hpp"
#include "tunekit/protocols/runner.hpp"
#include "tunekit/sim/simulator.hpp"

using tunekit::MachineError;
using namespace tunekit::machine;
using tunekit::sim::SimConfig;
using tunekit::sim::SimPtyServer;

namespace {

constexpr std::chrono::milliseconds kTimeout{3000};
// Characters RepRapFirmware's query parser treats specially ('+' is a space, '&' and '=' split).
const std::string kBoardPassword = "p@ss w+rd&x=1%";
const std::string kEncoded = "p%40ss%20w%2Brd%26x%3D1%25";

/// The environment variable set for one scope (tests run one per process under ctest).
class EnvPassword {
 public:
  explicit EnvPassword(const char* value) {
    if (value) ::setenv(kRrfPasswordEnv, value, 1);
    else ::unsetenv(kRrfPasswordEnv);
  }
  ~EnvPassword() { ::unsetenv(kRrfPasswordEnv); }
  EnvPassword(const EnvPassword&) = delete;
  EnvPassword& operator=(const EnvPassword&) = delete;
};

std::string connect_error(const HttpAddress& addr, const std::optional<std::string>& pw) {
  try {
    rrf_connect(addr, pw, kTimeout);
  } catch (const MachineError& e) {
    return e.what();
  }
  return "(no error)";
}

/// Every file of a run directory, concatenated.
std::string all_files(const std::string& dir) {
  std::string s;
  for (const auto& f : std::filesystem::recursive_directory_iterator(dir))
    if (f.is_regular_file()) s += tunekit::test::read_text(f.path().string());
  return s;
}

tunekit::protocols::RunOptions rrf_sweep(const std::string& dir, const std::string& board_password) {
  tunekit::protocols::RunOptions o;
  o.protocol = "axis-sweep";
  o.run_dir = dir + "/run";
  o.params = {{"freq_start_hz", 40}, {"freq_end_hz", 56}};
  tunekit::calibration::load_run_machine(
      o, "", {"firmware=rrf", "sensor_stream=0", "rrf_http=1", "accel_rate_hz=1344", "rrf_password=" + board_password});
  return o;
}

}  // namespace

TEST_CASE("RepRapFirmware's rr_connect: the right password opens a session, a wrong or missing one is refused",
          "[machine][rrf]") {
  SimPtyServer server(SimConfig::from_options({"firmware=rrf", "rrf_http=1", "rrf_password=" + kBoardPassword}));
  const auto addr = parse_http_address(server.http_url());
  // Without a session the protected board answers 401 to everything but rr_connect.
  CHECK(http_get(addr, "/rr_download?name=0%3A%2Fsys%2Fx.csv", kTimeout).status == 401);
  // The right password, percent-encoded: a session with a key, sent back as X-Session-Key.
  const auto s = rrf_connect(addr, kBoardPassword, kTimeout);
  CHECK(s.key != 0);
  const auto miss = http_get(addr, "/rr_download?name=0%3A%2Fsys%2Fx.csv", kTimeout,
                             "X-Session-Key: " + std::to_string(s.key) + "\r\n");
  CHECK(miss.status == 404);  // authorised: the file is what is missing
  CHECK_THROWS_WITH(rrf_download(s, "0:/sys/x.csv", kTimeout), Catch::Contains("404"));
  const auto targets = server.http_targets();
  REQUIRE(!targets.empty());
  CHECK(std::count_if(targets.begin(), targets.end(), [](const std::string& t) {
          return t.rfind("/rr_connect?password=" + kEncoded + "&time=", 0) == 0;
        }) == 1);
  rrf_disconnect(s, kTimeout);
  CHECK(http_get(addr, "/rr_download?name=x", kTimeout, "X-Session-Key: " + std::to_string(s.key) + "\r\n").status ==
        401);
  // A wrong password: the one clear sentence, without the password.
  const std::string wrong = connect_error(addr, std::string("hunter2 secret"));
  CHECK(wrong.find("RepRapFirmware refused the password") != std::string::npos);
  CHECK(wrong.find("hunter2") == std::string::npos);
  // None given on a protected board: says so, and where to give it.
  const std::string none = connect_error(addr, std::nullopt);
  CHECK(none.find("protected by a password") != std::string::npos);
  CHECK(none.find(kRrfPasswordEnv) != std::string::npos);
}

TEST_CASE("RepRapFirmware's rr_connect: no free session, and a board without a password", "[machine][rrf]") {
  SimPtyServer full(SimConfig::from_options({"firmware=rrf", "rrf_http=1", "rrf_http_sessions=1"}));
  const auto addr = parse_http_address(full.http_url());
  // Without M551 the default password (and any request) opens a session.
  const auto first = rrf_connect(addr, std::nullopt, kTimeout);
  CHECK(connect_error(addr, std::nullopt).find("no HTTP session free") != std::string::npos);
  rrf_disconnect(first, kTimeout);
  CHECK(connect_error(addr, std::nullopt) == "(no error)");
  SimPtyServer open(SimConfig::from_options({"firmware=rrf", "rrf_http=1"}));
  CHECK_THROWS_WITH(rrf_download(parse_http_address(open.http_url()), "0:/sys/none.csv", kTimeout),
                    Catch::Contains("404"));
}

TEST_CASE("the RepRapFirmware password: the environment wins over the profile, empty means none", "[machine][rrf]") {
  {
    const EnvPassword env(nullptr);
    CHECK_FALSE(rrf_password(""));
    CHECK(*rrf_password("from-profile") == "from-profile");
  }
  {
    const EnvPassword env("from-env");
    CHECK(*rrf_password("from-profile") == "from-env");
  }
  {
    const EnvPassword env("");
    CHECK(*rrf_password("from-profile") == "from-profile");
  }
  const auto p = parse_machine_profile(tunekit::test::read_text(tunekit::test::dataset("machines/sim.toml")) +
                                           "\n[network]\nhttp = \"http://duet.local\"\npassword = \"x y\"\n",
                                       "net.toml");
  CHECK(p.http_password == "x y");
}

TEST_CASE("axis-sweep on a password-protected RepRapFirmware fetches its file and never shows the password",
          "[machine][rrf]") {
  const std::string dir = tunekit::test::scratch_dir("rrf_password_sweep");
  const EnvPassword env(kBoardPassword.c_str());
  auto o = rrf_sweep(dir, kBoardPassword);
  std::string progress;
  o.progress = [&](const std::string& m) { progress += m + "\n"; };
  const auto res = tunekit::protocols::run_experiment(o);
  REQUIRE(res.status == "complete");
  REQUIRE(res.files.count(tunekit::protocols::RunFile::accel));
  const std::string everything = all_files(res.run_dir) + progress;
  CHECK(everything.find("rrf_tunekit_1.csv") != std::string::npos);
  CHECK(everything.find(kBoardPassword) == std::string::npos);
  CHECK(everything.find(kEncoded) == std::string::npos);
}

TEST_CASE("a wrong or missing RepRapFirmware password is one clear error, exit 3, before heating or homing",
          "[machine][rrf]") {
  const std::string dir = tunekit::test::scratch_dir("rrf_password_refused");
  const std::string typed = "Wr0ng-pa55";
  auto cli = [&](const std::string& sub) {
    return tunekit::test::run_cli({"run", "axis-sweep", "--sim", "firmware=rrf", "--sim", "sensor_stream=0", "--sim",
                                   "rrf_http=1", "--sim", "rrf_password=" + kBoardPassword, "--run-dir",
                                   dir + "/" + sub});
  };
  {
    const EnvPassword env(typed.c_str());
    const auto r = cli("wrong");
    CHECK(r.code == 3);
    // One error line, and it is the refusal.
    const auto at = r.err.find("tunekit: error: ");
    REQUIRE(at != std::string::npos);
    CHECK(r.err.find("tunekit: error: ", at + 1) == std::string::npos);
    CHECK(r.err.find("RepRapFirmware refused the password", at) < r.err.find('\n', at));
    CHECK((r.out + r.err + all_files(dir + "/wrong")).find(typed) == std::string::npos);
    const std::string received = tunekit::test::read_text(dir + "/wrong/sim_received.gcode");
    CHECK(received.find("M115") != std::string::npos);
    for (const char* never : {"G28", "M109", "M956", "G1 "}) {
      INFO(never);
      CHECK(received.find(never) == std::string::npos);
    }
    // A dry run does not log in, and shows no password either.
    const auto dry = tunekit::test::run_cli({"run", "axis-sweep", "--sim", "firmware=rrf", "--dry-run"});
    CHECK(dry.code == 0);
    CHECK((dry.out + dry.err).find(typed) == std::string::npos);
  }
  const EnvPassword none(nullptr);
  const auto r = cli("missing");
  CHECK(r.code == 3);
  CHECK(r.err.find("protected by a password (M551) and none was given") != std::string::npos);
}
