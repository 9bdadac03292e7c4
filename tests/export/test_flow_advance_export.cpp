// Flow-dependent advance written out: Kalico's printer.cfg options, an OrcaSlicer filament
// profile merged in place (on a published OrcaSlicer profile), and the per-feature G-code
// post-processor.
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <nlohmann/json.hpp>
#include <sstream>

#include "test_support.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/design/flow_advance.hpp"
#include "tunekit/firmware/firmware_export.hpp"
#include "tunekit/firmware/gcode_advance.hpp"
#include "tunekit/firmware/orca_profile.hpp"

using namespace tunekit;

namespace {

std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::vector<design::OrcaPoint> sample_table() {
  // Deliberately unsorted, with values needing rounding.
  return {{0.04123, 9.004, 5000}, {0.05871, 1.5, 5000}, {0.0499, 4.25, 5000}, {0.0371, 15.999, 5000}};
}

std::vector<std::string> split_keep(const std::string& s) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : s) {
    cur += c;
    if (c == '\n') {
      out.push_back(cur);
      cur.clear();
    }
  }
  if (!cur.empty()) out.push_back(cur);
  return out;
}

/// A sliced-looking file: per layer an external perimeter (slow), perimeters, infill (fast),
/// top solid infill; PrusaSlicer's comment spelling, relative E, 0.45 x 0.2 mm lines.
std::string generated_gcode(const std::string& eol) {
  std::ostringstream g;
  g << "; generated for the tunekit post-processor test" << eol << "; filament_diameter = 1.75" << eol << "G90" << eol
    << "M83" << eol << "SET_PRESSURE_ADVANCE ADVANCE=0.045" << eol << "G1 Z0.2 F720" << eol;
  const double line_area = 0.45 * 0.2, fil_area = M_PI * 0.875 * 0.875;
  const std::vector<std::pair<std::string, double>> features = {
      {"External perimeter", 1500}, {"Perimeter", 2700}, {"Internal infill", 9000}, {"Solid infill", 8400}};
  for (int layer = 0; layer < 6; ++layer) {
    g << ";LAYER_CHANGE" << eol << ";Z:" << 0.2 * (layer + 1) << eol;
    for (const auto& [name, f] : features) {
      g << ";TYPE:" << name << eol << ";WIDTH:0.45" << eol << "G1 X10 Y10 F9000" << eol;
      double x = 10;
      for (int s = 0; s < 5; ++s) {
        x += 8;
        g << "G1 X" << x << " Y10 E" << 8 * line_area / fil_area << " F" << f << eol;
      }
    }
  }
  g << "M107" << eol;
  return g.str();
}

std::vector<std::pair<double, double>> k_table() { return {{1.0, 0.060}, {4.0, 0.048}, {10.0, 0.038}, {20.0, 0.031}}; }

}  // namespace

TEST_CASE("kalico export: the nonlinear model replaces pressure_advance in [extruder], byte-exact elsewhere") {
  const std::string cfg =
      "[printer]\nkinematics: corexy\n\n[extruder]\nstep_pin: PA1\npressure_advance: 0.04  # old\n"
      "pressure_advance_smooth_time: 0.03\n\n[heater_bed]\nheater_pin: PB1\n";
  firmware::CompensatorSettings s;
  firmware::KalicoAdvanceSetting k;
  k.model = "recipr";
  k.linear_advance_s = 0.012;
  k.nonlinear_offset_mm = 0.11;
  k.linearization_velocity_mm_s = 1.7;
  k.time_offset_s = 0.004;
  s.kalico = k;
  const auto r = firmware::export_config_text(firmware::ExportFirmware::kalico, cfg, "printer.cfg", s);
  CHECK(r.updated ==
        "[printer]\nkinematics: corexy\n\n[extruder]\nstep_pin: PA1\n#pressure_advance: 0.04  # old\n"
        "pressure_advance_smooth_time: 0.03\npressure_advance_model: recipr\nlinear_advance: 0.012\n"
        "nonlinear_offset: 0.11\nlinearization_velocity: 1.7\npressure_advance_time_offset: 0.004\n\n"
        "[heater_bed]\nheater_pin: PB1\n");
  CHECK(r.gcode.find("SET_PRESSURE_ADVANCE MODEL=recipr ADVANCE=0.012 OFFSET=0.11 VELOCITY=1.7 TIME_OFFSET=0.004") !=
        std::string::npos);
  // Idempotent: a second run changes nothing.
  CHECK_FALSE(firmware::export_config_text(firmware::ExportFirmware::kalico, r.updated, "printer.cfg", s).changed());
  // Kalico's bounds.
  auto bad = s;
  bad.kalico->time_offset_s = 0.25;
  CHECK_THROWS_AS(firmware::export_config_text(firmware::ExportFirmware::kalico, cfg, "printer.cfg", bad), InputError);
  bad = s;
  bad.kalico->linearization_velocity_mm_s = 0;
  CHECK_THROWS_AS(firmware::export_config_text(firmware::ExportFirmware::kalico, cfg, "printer.cfg", bad), InputError);
  bad = s;
  bad.kalico->nonlinear_offset_mm = std::nan("");
  CHECK_THROWS_AS(firmware::export_config_text(firmware::ExportFirmware::kalico, cfg, "printer.cfg", bad), InputError);
  CHECK_THROWS_AS(firmware::export_config_text(firmware::ExportFirmware::klipper, cfg, "printer.cfg", s), InputError);
}

TEST_CASE("orca profile: the model text is sorted by flow and rounded as OrcaSlicer writes it") {
  CHECK(firmware::orca_model_text(sample_table()) == "0.059,1.5,5000\n0.05,4.25,5000\n0.041,9,5000\n0.037,16,5000");
  auto t = sample_table();
  t[0].k_s = std::nan("");
  CHECK_THROWS_AS(firmware::orca_model_text(t), InputError);
  t = sample_table();
  t[1].flow_mm3_s = 9.001;  // coincides with 9.004 after rounding
  CHECK_THROWS_AS(firmware::orca_model_text(t), InputError);
}

TEST_CASE("orca profile merge on a published OrcaSlicer filament profile keeps every untouched key byte-identical") {
  const std::string path = tunekit::test::dataset("slicer/orca_phrozen_pla_arco_0.4.json");
  const std::string original = read_bytes(path);
  REQUIRE(original.size() == 5544);
  firmware::OrcaAdvanceProfile p;
  p.table = sample_table();
  p.fallback_k_s = 0.0452;
  const auto r = firmware::merge_orca_filament_profile(original, p, path);

  const auto before = firmware::json_top_level_members(original, path);
  const auto after = firmware::json_top_level_members(r.text, path);
  std::map<std::string, std::string> after_map(after.begin(), after.end());
  const std::set<std::string> touched = {"adaptive_pressure_advance", "adaptive_pressure_advance_model",
                                         "enable_pressure_advance", "pressure_advance"};
  std::size_t untouched = 0;
  for (const auto& [key, raw] : before) {
    if (touched.count(key)) continue;
    ++untouched;
    INFO(key);
    REQUIRE(after_map.count(key) == 1);
    CHECK(after_map[key] == raw);  // byte-identical member text, CRLF and indentation included
  }
  CHECK(untouched == before.size() - 3);  // the file has three of the four keys
  // Member order kept; the missing key appended at the end.
  for (std::size_t i = 0; i < before.size(); ++i) CHECK(after[i].first == before[i].first);
  CHECK(after.back().first == "adaptive_pressure_advance");
  CHECK(r.added_keys == std::vector<std::string>{"adaptive_pressure_advance"});

  const auto j = nlohmann::json::parse(r.text);
  CHECK(j["adaptive_pressure_advance"] == nlohmann::json::array({"1"}));
  CHECK(j["pressure_advance"] == nlohmann::json::array({"0.045"}));
  const std::string model = j["adaptive_pressure_advance_model"][0].get<std::string>();
  CHECK(model == "0.059,1.5,5000\n0.05,4.25,5000\n0.041,9,5000\n0.037,16,5000");
  // The appended member follows the file's style (CRLF, 4 + 8 spaces).
  CHECK(r.text.find(",\r\n    \"adaptive_pressure_advance\": [\r\n        \"1\"\r\n    ]\r\n}") != std::string::npos);
  // The bytes outside the edited values are those of the original (the edit is local): the
  // text up to the first touched member is a common prefix.
  const auto first = original.find("\"adaptive_pressure_advance_model\"");
  CHECK(r.text.compare(0, first, original, 0, first) == 0);
  // Merging again changes nothing.
  CHECK(firmware::merge_orca_filament_profile(r.text, p, path).text == r.text);
  // OrcaSlicer's own table in this profile has the format written here (3 / <=2 / 0 decimals).
  CHECK(original.find("0.042,0.72,5000\\n0.044,1.44,5000") != std::string::npos);
}

TEST_CASE("orca profile: a new profile, and bad inputs") {
  firmware::OrcaAdvanceProfile p;
  p.table = sample_table();
  p.fallback_k_s = 0.045;
  const auto j = nlohmann::json::parse(firmware::new_orca_filament_profile(p, "PLA tunekit", "Generic PLA"));
  CHECK(j["type"] == "filament");
  CHECK(j["inherits"] == "Generic PLA");
  CHECK(j["adaptive_pressure_advance"][0] == "1");
  CHECK_THROWS_AS(firmware::merge_orca_filament_profile("[1, 2]", p, "x.json"), InputError);
  CHECK_THROWS_AS(firmware::merge_orca_filament_profile("{\"type\": \"process\", \"a\": 1}", p, "x.json"), InputError);
  CHECK_THROWS_AS(firmware::merge_orca_filament_profile("{\"a\": ", p, "x.json"), InputError);
  p.fallback_k_s = -1;
  CHECK_THROWS_AS(firmware::merge_orca_filament_profile("{\"a\": 1}", p, "x.json"), InputError);
}

TEST_CASE("gcode post-processor keeps every non-advance line byte-identical and respects its hysteresis") {
  for (const std::string eol : {"\n", "\r\n"}) {
    const std::string original = generated_gcode(eol);
    firmware::GcodeAdvanceOptions o;
    o.firmware = firmware::ExportFirmware::klipper;
    o.k_of_flow = k_table();
    o.hysteresis = 0.10;
    const auto r = firmware::apply_gcode_advance(original, o, "sliced.gcode");
    CHECK(r.features == 24);
    REQUIRE_FALSE(r.changes.empty());
    // Dropping the inserted lines gives the original back, byte for byte.
    std::string stripped;
    std::size_t inserted = 0;
    for (const auto& l : split_keep(r.text)) {
      if (l.rfind("SET_PRESSURE_ADVANCE", 0) == 0 && l.find("; tunekit:") != std::string::npos) {
        ++inserted;
        CHECK(l.substr(l.size() - eol.size()) == eol);
        continue;
      }
      stripped += l;
    }
    CHECK(stripped == original);
    CHECK(inserted == r.changes.size());
    // Each change moves the advance by more than the hysteresis from the active value (the
    // file's own 0.05 at first).
    double active = 0.045;
    for (const auto& c : r.changes) {
      CHECK(std::abs(c.k_s - active) > o.hysteresis * active);
      active = c.k_s;
    }
    // The four features alternate every layer; the solid infill's K is within 10 % of the
    // internal infill's before it, so it never causes a change: three changes per layer.
    CHECK(r.changes.size() == 18);
    for (const auto& c : r.changes) CHECK(c.feature != "Solid infill");
    // A wide hysteresis: at most one change (the infill's K is 25 % below the perimeter's).
    o.hysteresis = 0.5;
    CHECK(firmware::apply_gcode_advance(original, o, "sliced.gcode").changes.size() <= 1);
  }
}

TEST_CASE("gcode post-processor: the flow of a feature and the firmware's command") {
  // One feature at 0.45 x 0.2 mm and 50 mm/s: 4.5 mm^3/s.
  const double fa = M_PI * 0.875 * 0.875;
  std::ostringstream g;
  g << "M83\n;TYPE:Internal infill\nG1 X0 Y0 F6000\nG1 X20 Y0 E" << 20 * 0.09 / fa << " F3000\n";
  firmware::GcodeAdvanceOptions o;
  o.firmware = firmware::ExportFirmware::marlin;
  o.k_of_flow = k_table();
  o.filament_area_mm2 = fa;
  const auto r = firmware::apply_gcode_advance(g.str(), o, "a.gcode");
  REQUIRE(r.changes.size() == 1);
  CHECK(r.changes[0].flow_mm3_s == Catch::Detail::Approx(4.5).epsilon(1e-6));
  CHECK(r.text.find(";TYPE:Internal infill\nM900 K0.0472 ; tunekit: Internal infill at 4.5 mm^3/s\n") !=
        std::string::npos);
  o.firmware = firmware::ExportFirmware::rrf;
  CHECK(firmware::apply_gcode_advance(g.str(), o, "a.gcode").text.find("M572 D0 S0.0472") != std::string::npos);
  // No diameter known, no features, a value beyond the firmware's bounds: refused.
  o.filament_area_mm2 = 0;
  CHECK_THROWS_AS(firmware::apply_gcode_advance(g.str(), o, "a.gcode"), InputError);
  o.filament_area_mm2 = fa;
  CHECK_THROWS_AS(firmware::apply_gcode_advance("G1 X1 E1\n", o, "a.gcode"), InputError);
  o.firmware = firmware::ExportFirmware::marlin;
  o.k_of_flow = {{1.0, 12.0}, {2.0, 11.0}};
  CHECK_THROWS_AS(firmware::apply_gcode_advance(g.str(), o, "a.gcode"), InputError);
}

TEST_CASE("tunekit export of a flow sweep: Kalico config, merged OrcaSlicer profile, per-feature G-code and plot") {
  const std::string dir = tunekit::test::scratch_dir("flow_advance_export");
  const std::string cfg = dir + "/printer.cfg";
  std::filesystem::copy_file(tunekit::test::dataset("firmware/printer.cfg"), cfg,
                             std::filesystem::copy_options::overwrite_existing);
  const std::string sliced = tunekit::test::write_scratch("flow_advance_sliced.gcode", generated_gcode("\n"));
  const std::string orca_in = tunekit::test::dataset("slicer/orca_phrozen_pla_arco_0.4.json");
  const std::string sweep = tunekit::test::dataset("../tests/export/fixtures/step_sweep.json");
  const auto r = tunekit::test::run_cli({"export",
                                         "-f",
                                         "kalico",
                                         "-c",
                                         cfg,
                                         "-p",
                                         tunekit::test::dataset("machines/sim.toml"),
                                         sweep,
                                         "--orca-in",
                                         orca_in,
                                         "--orca-out",
                                         dir + "/orca.json",
                                         "--gcode-in",
                                         sliced,
                                         "--gcode-out",
                                         dir + "/tuned.gcode",
                                         "--plot",
                                         dir + "/flow.svg",
                                         "--json",
                                         "--write"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto j = nlohmann::json::parse(r.out)["results"];
  const auto& fa = j["flow_advance"];
  REQUIRE(fa.is_object());
  CHECK(fa["has_band"] == true);
  CHECK(fa["kalico"]["max_rel_error"].get<double>() < 0.05);
  // The Kalico options are in the written printer.cfg.
  const std::string after = tunekit::test::read_text(cfg);
  CHECK(after.find("pressure_advance_model: " + fa["kalico"]["pressure_advance_model"].get<std::string>()) !=
        std::string::npos);
  CHECK(after.find("nonlinear_offset: ") != std::string::npos);
  CHECK(after.find("pressure_advance_time_offset: 0.02") != std::string::npos);
  // The OrcaSlicer profile: merged, the table sorted by flow.
  const auto orca = nlohmann::json::parse(tunekit::test::read_text(dir + "/orca.json"));
  CHECK(orca["adaptive_pressure_advance"][0] == "1");
  CHECK(orca["name"] == "Phrozen PLA @Phrozen Arco 0.4 nozzle");
  // The G-code: changes recorded, the original lines kept.
  CHECK(j["gcode_post"]["changes"].size() >= 1);
  std::string stripped;
  for (const auto& l : split_keep(tunekit::test::read_text(dir + "/tuned.gcode")))
    if (l.find("; tunekit:") == std::string::npos) stripped += l;
  CHECK(stripped == generated_gcode("\n"));
  CHECK(std::filesystem::file_size(dir + "/flow.svg") > 1000);
}
