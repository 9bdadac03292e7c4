// Every command opens each of its input files once, and so does a guided calibration: the digest
// recorded for an input is of the bytes the analysis read, not of a second reading. Counted with
// core::FileOpenLog, which records every file the file layer opens.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <thread>

#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include "test_support.hpp"
#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/core/atomic_file.hpp"
#include "tunekit/core/file_bytes.hpp"
#include "tunekit/core/file_open_log.hpp"
#include "tunekit/vision/image_io.hpp"

namespace {

namespace fs = std::filesystem;
using tunekit::core::FileOpenLog;
using tunekit::test::run_cli;

std::string copy_into(const std::string& dir, const std::string& file) {
  const std::string to = dir + "/" + fs::path(file).filename().string();
  fs::copy_file(file, to, fs::copy_options::overwrite_existing);
  return to;
}

std::string opened_list(const FileOpenLog& log) {
  std::string s;
  for (const auto& p : log.paths()) s += "\n  " + p;
  return s;
}

// Runs `tunekit ARGS` in-process with a log alive; each of `inputs` must have been opened exactly
// once, and no file more than once. Returns the run (its exit code is checked to be 0).
tunekit::test::CliRun check_read_once(const std::vector<std::string>& args, const std::vector<std::string>& inputs) {
  FileOpenLog log;
  const auto r = run_cli(args);
  INFO(args.front() << ": " << r.err << "\nopened:" << opened_list(log));
  REQUIRE(r.code == 0);
  for (const auto& in : inputs) {
    INFO(in);
    CHECK(log.opens(in) == 1);
  }
  for (const auto& p : log.paths()) {
    INFO(p);
    CHECK(log.opens(p) == 1);
  }
  return r;
}

// The default simulated calibration's run directory (its files are the commands' inputs here).
std::string sim_run() {
  const auto& run = tunekit::test::default_calibration();
  REQUIRE(run.cli.code == 0);
  return run.dir;
}

}  // namespace

TEST_CASE("the file open log records every file the file layer opens while it is alive, on any thread") {
  const std::string a = tunekit::test::write_scratch("open_log_a.txt", "a");
  const std::string b = tunekit::test::write_scratch("open_log_b.txt", "bb");
  (void)tunekit::read_file_bytes(a);  // no log alive: not recorded anywhere
  FileOpenLog outer;
  (void)tunekit::read_file_bytes(a);
  {
    FileOpenLog inner;
    const tunekit::MappedFileBytes mapped(b);
    CHECK(mapped.view() == "bb");
    (void)tunekit::read_file_head(a, 1);
    CHECK(inner.opens(b) == 1);
    CHECK(inner.opens(a) == 1);
  }
  std::vector<std::thread> threads;
  for (int i = 0; i < 4; ++i)
    threads.emplace_back([&] {
      for (int k = 0; k < 25; ++k) (void)tunekit::read_file_bytes(b);
    });
  for (auto& t : threads) t.join();
  CHECK(outer.opens(a) == 2);
  CHECK(outer.opens(fs::path(b).parent_path().string() + "/./" + fs::path(b).filename().string()) == 101);
  CHECK(outer.paths().size() == 103);
  CHECK_THROWS(tunekit::read_file_bytes(a + ".missing"));
  CHECK(outer.opens(a + ".missing") == 1);  // an open that fails is an open too
}

TEST_CASE("step (with its figure) and freq open the log and its feed track once each") {
  const std::string run = sim_run();
  const std::string step_csv = run + "/liquefier-step/step.csv", step_track = run + "/liquefier-step/feed_track.csv";
  const std::string plot = tunekit::test::scratch_dir("read_once_step") + "/step.svg";
  // With --plot too: the figure draws the record as the analysis read it.
  const auto s = check_read_once(
      {"step", step_csv, "--input", "feed", "--output", "force", "--feed-track", step_track, "--plot", plot, "--json"},
      {step_csv, step_track});
  CHECK(fs::file_size(plot) > 1000);
  // The digest recorded is that of the file's bytes.
  CHECK(nlohmann::json::parse(s.out)["inputs"][0]["sha256"] ==
        tunekit::calibration::sha256_hex(tunekit::read_file_bytes(step_csv)));
  const std::string chirp = run + "/liquefier-chirp/feed_force.csv",
                    chirp_track = run + "/liquefier-chirp/feed_track.csv";
  check_read_once({"freq", chirp, "--input", "feed", "--output", "force", "--json"}, {chirp, chirp_track});
}

TEST_CASE("resonance, shaper and overshoot open each accelerometer record once") {
  const std::string run = sim_run();
  const std::string raw = run + "/axis-x/raw_data_x_tunekit.csv";
  const std::string motion = run + "/axis-x/commanded_motion_x_tunekit.csv";
  check_read_once({"resonance", raw, "--axis", "x", "--json"}, {raw});
  check_read_once({"shaper", raw, "--axis", "x", "--json"}, {raw, motion});

  const auto dir = tunekit::test::scratch_dir("read_once_overshoot") + "/run";
  const auto rect = run_cli({"run", "axis-rectangle", "--machine", "sim", "--run-dir", dir, "-p", "speed_mm_s=150",
                             "-p", "accel_mm_s2=5000", "-p", "pause_s=0.6", "-p", "repeats=2", "--json"});
  INFO(rect.err);
  REQUIRE(rect.code == 0);
  std::vector<std::string> records;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (name.rfind("raw_data_", 0) == 0 || name.rfind("commanded_accel_", 0) == 0) records.push_back(e.path().string());
  }
  REQUIRE(records.size() == 2);
  check_read_once({"overshoot", dir, "--band-mm", "0.01", "--json"}, records);
}

TEST_CASE("rheo, nozzle, belts and delta open each input once") {
  const std::string dir = tunekit::test::scratch_dir("read_once_rheo");
  const std::string rheo_csv = tunekit::test::dataset("rheology/peek_cross_wlf_synthetic.csv");
  const std::string rheo_json = dir + "/rheo.json";
  check_read_once({"rheo", rheo_csv, "--model", "cross-wlf", "--json", "-o", rheo_json}, {rheo_csv});
  check_read_once({"nozzle", "--rheology", rheo_json, "--temperature", "400", "--flow", "5", "--json"}, {rheo_json});
  const std::string a = tunekit::test::dataset("belts/adxl345-belt_A_1_cut.csv");
  const std::string b = tunekit::test::dataset("belts/adxl345-belt_A_2_cut.csv");
  check_read_once({"belts", a, b, "--json"}, {a, b});
  const std::string probes = tunekit::test::dataset("delta/probes_simulated.csv");
  check_read_once({"delta", probes, "--radius", "105", "--rod", "215", "--height", "250", "--json"}, {probes});
}

TEST_CASE("export opens the results files, the configuration and the machine profile once each") {
  const std::string run = sim_run();
  const std::string dir = tunekit::test::scratch_dir("read_once_export");
  const std::string config = copy_into(dir, run + "/config/printer.cfg");
  const std::string step = copy_into(dir, run + "/analysis/step.json");
  const std::string shaper = copy_into(dir, run + "/analysis/shaper_x.json");
  const std::string profile = tunekit::test::dataset("machines/sim.toml");
  check_read_once({"export", "-f", "klipper", "-c", config, "--profile", profile, step, shaper, "--json"},
                  {config, profile, step, shaper});
}

TEST_CASE("linewidth opens each photo once") {
  const std::string dir = tunekit::test::scratch_dir("read_once_linewidth");
  cv::Mat img(300, 1000, CV_8UC1, cv::Scalar(200));
  cv::line(img, {50, 150}, {950, 150}, cv::Scalar(40), 8);
  cv::GaussianBlur(img, img, {5, 5}, 1.0);
  const std::string photo = dir + "/line.png";
  tunekit::vision::write_png(photo, img);
  check_read_once({"linewidth", photo, "--px-per-mm", "10", "--json"}, {photo});
}

TEST_CASE("calibrate opens each record it analyses once and records the digests of those bytes") {
  for (const std::vector<std::string>& extra : {std::vector<std::string>{}, {"--liquefier", "camera"}}) {
    const std::string dir = tunekit::test::scratch_dir(extra.empty() ? "read_once_cal" : "read_once_cal_cam") + "/run";
    std::vector<std::string> args{"calibrate", "--machine", "sim", "--out", dir};
    args.insert(args.end(), extra.begin(), extra.end());
    FileOpenLog log;
    const auto r = run_cli(args);
    INFO(r.err << "\nopened:" << opened_list(log));
    REQUIRE(r.code == 0);
    for (const auto& p : log.paths()) {
      INFO(p);
      CHECK(log.opens(p) == 1);
    }
    const auto results = tunekit::test::read_json(dir + "/results.json");
    REQUIRE(results["inputs"].size() >= 3);
    for (const auto& in : results["inputs"]) {
      const std::string path = dir + "/" + in["path"].get<std::string>();
      INFO(path);
      // The camera path's photo (the simulated camera's), width record and feed track are analysed
      // as the run wrote them, not read back.
      const bool written_by_run = !extra.empty() && path.find("/liquefier-camera/") != std::string::npos;
      CHECK(log.opens(path) == (written_by_run ? 0u : 1u));
      CHECK(in["sha256"] == tunekit::calibration::sha256_hex(tunekit::read_file_bytes(path)));
    }
    // The analyses' JSON files export designs from are digested as written, not read back.
    for (const char* json : {"analysis/step.json", "analysis/shaper_x.json", "analysis/shaper_y.json"}) {
      INFO(json);
      CHECK(log.opens(dir + "/" + json) == 0);
    }
  }
}

TEST_CASE("calibrate with a profile file opens it once: the export records the digest of the bytes the plan read") {
  const std::string dir = tunekit::test::scratch_dir("read_once_cal_profile");
  const std::string profile = dir + "/printer.toml";
  tunekit::core::write_file_atomic(profile, tunekit::read_file_bytes(tunekit::test::dataset("machines/sim.toml")));
  FileOpenLog log;
  const auto r =
      run_cli({"calibrate", "--machine", "sim", "--profile", profile, "--skip-liquefier", "--out", dir + "/run"});
  INFO(r.err << "\nopened:" << opened_list(log));
  REQUIRE(r.code == 0);
  CHECK(log.opens(profile) == 1);
  const auto exported = tunekit::test::read_json(dir + "/run/analysis/export.json");
  bool recorded = false;
  for (const auto& in : exported["inputs"])
    if (in["path"] == profile) {
      recorded = true;
      CHECK(in["sha256"] == tunekit::calibration::sha256_hex(tunekit::read_file_bytes(profile)));
    }
  CHECK(recorded);
}

TEST_CASE("a firmware configuration given as the profile is opened once, its includes once each") {
  // Klipper's own example with an include beside it, a Marlin Configuration.h (with its
  // Configuration_adv.h) and an RRF config.g: the format's check, the importer and the
  // firmware's parser read each by path, the file layer opens it once.
  const std::string dir = tunekit::test::scratch_dir("read_once_profiles");
  const std::string cfg = dir + "/printer.cfg", inc = dir + "/macros.cfg";
  tunekit::core::write_file_atomic(
      cfg, "[include macros.cfg]\n" +
               tunekit::read_file_bytes(tunekit::test::dataset("klipper_configs/printer-creality-ender3-2018.cfg")));
  tunekit::core::write_file_atomic(inc, "[gcode_macro PARK]\ngcode:\n  G28\n");
  for (const std::vector<std::string>& args : {std::vector<std::string>{"profile", cfg},
                                               {"calibrate", "--machine", "sim", "--profile", cfg, "--sensor",
                                                "accelerometer", "--dry-run", "--out", dir + "/run"}}) {
    FileOpenLog log;
    const auto r = run_cli(args);
    INFO(args[0] << "\n" << r.err << "\nopened:" << opened_list(log));
    REQUIRE(r.code == 0);
    CHECK(log.opens(cfg) == 1);
    CHECK(log.opens(inc) == 1);
    for (const auto& p : log.paths()) {
      INFO(p);
      CHECK(log.opens(p) == 1);
    }
  }
}
