// Hostile input files: located errors instead of internal ones for bad results JSON, images
// whose headers claim gigapixels refused before decoding, one wild accelerometer sample that
// does not erase a result, and byte-order marks in CSV files.
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "../resonance/synth_sweep.hpp"
#include "test_support.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/vision/image_io.hpp"

using tunekit::test::run_cli;
using tunekit::test::scratch_dir;
namespace fs = std::filesystem;

namespace {

std::string write_file(const std::string& dir, const std::string& name, const std::string& bytes) {
  const std::string p = dir + "/" + name;
  std::ofstream(p, std::ios::binary) << bytes;
  return p;
}

std::string le32(std::uint32_t v) {
  std::string s(4, '\0');
  for (int i = 0; i < 4; ++i) s[static_cast<std::size_t>(i)] = static_cast<char>((v >> (8 * i)) & 0xFF);
  return s;
}

/// A BMP whose header claims width x height pixels of 24 bit but holds only `payload` bytes.
std::string bmp_claiming(std::uint32_t width, std::uint32_t height, std::size_t payload) {
  std::string h = "BM" + le32(static_cast<std::uint32_t>(54 + payload)) + le32(0) + le32(54);
  h += le32(40) + le32(width) + le32(height) + std::string("\x01\x00\x18\x00", 4) + le32(0) +
       le32(static_cast<std::uint32_t>(payload)) + le32(2835) + le32(2835) + le32(0) + le32(0);
  return h + std::string(payload, '\x40');
}

}  // namespace

TEST_CASE("bad results JSON is a located input error, not an internal error", "[safety]") {
  const auto dir = scratch_dir("hostile_results_json");
  const std::string cfg = write_file(dir, "printer.cfg", "[extruder]\npressure_advance: 0.02\n");
  const auto overflow =
      write_file(dir, "overflow.json", "{\n  \"command\": \"step\",\n  \"results\": {\"x\": 1e400}\n}\n");
  auto r = run_cli({"export", "-f", "klipper", "-c", cfg, overflow});
  CHECK(r.code == 2);
  CHECK(r.err.find(overflow + ":3:") != std::string::npos);
  CHECK(r.err.find("beyond the range of a double") != std::string::npos);
  const auto type = write_file(dir, "type.json", "{\n  \"command\": 5,\n  \"results\": {}\n}\n");
  r = run_cli({"export", "-f", "klipper", "-c", cfg, type});
  CHECK(r.code == 2);
  CHECK(r.err.find(type + ":2: \"command\" must be a string") != std::string::npos);
  const auto syntax = write_file(dir, "syntax.json", "{\n  \"command\": \"step\",\n  \"results\": {,}\n}\n");
  r = run_cli({"export", "-f", "klipper", "-c", cfg, syntax});
  CHECK(r.code == 2);
  CHECK(r.err.find(syntax + ":3:") != std::string::npos);
  CHECK(r.err.find("internal error") == std::string::npos);

  // report on a run directory whose results.json is hostile.
  for (const std::string& body : {std::string("{\"command\": 5}"), std::string("{\"results\": null}"),
                                  std::string("{\"results\": {\"summary\": [{\"path\": 5}]}}"), std::string("[1, 2]"),
                                  std::string("{\"warnings\": [1]}"), std::string("{\"x\": 1e400}")}) {
    const auto run = scratch_dir("hostile_report_run");
    write_file(run, "results.json", body);
    const auto rr = run_cli({"report", run});
    INFO(body << ": " << rr.err);
    CHECK(rr.code == 2);
    CHECK(rr.err.find(run + "/results.json") != std::string::npos);
    CHECK(rr.err.find("internal error") == std::string::npos);
  }
}

TEST_CASE("images whose header claims too many pixels are refused before decoding", "[safety]") {
  using tunekit::vision::decode_image;
  const auto t0 = std::chrono::steady_clock::now();
  // A 7 KB BMP claiming 9,437,280 x 64 pixels; a top-down BMP (negative height) claiming
  // 14852 x 45747 (a libFuzzer finding: the negative height passed the check); PGMs claiming
  // 30000^2 and 46000^2.
  for (const std::string& bytes : {bmp_claiming(9437280, 64, 7000), bmp_claiming(14852, 0xFFFF4D4Du, 16),
                                   std::string("P5\n30000 30000\n255\n") + std::string(100, 'x'),
                                   std::string("P5\n46000 46000\n255\n") + std::string(100, 'x')}) {
    try {
      decode_image(bytes, "claim.img");
      FAIL("decoded");
    } catch (const tunekit::InputError& e) {
      CHECK(e.message().find("exceeds the limit of 100.0 MP") != std::string::npos);
      CHECK(e.location() == "claim.img");
    }
  }
  CHECK(std::chrono::steady_clock::now() - t0 < std::chrono::seconds(2));
  // Through the CLI, and the limit can be changed.
  const auto dir = scratch_dir("hostile_images");
  const auto bmp = write_file(dir, "huge.bmp", bmp_claiming(9437280, 64, 7000));
  const auto r = run_cli({"linewidth", bmp, "--px-per-mm", "20"});
  CHECK(r.code == 2);
  CHECK(r.err.find(bmp + ": image of 9437280 x 64 pixels") != std::string::npos);
  std::string pgm = "P5\n2000 1000\n255\n" + std::string(2000 * 1000, '\x80');
  const auto small = write_file(dir, "two_mp.pgm", pgm);
  const auto limited = run_cli({"linewidth", small, "--px-per-mm", "20", "--max-image-mp", "1"});
  CHECK(limited.code == 2);
  CHECK(limited.err.find("exceeds the limit of 1.0 MP") != std::string::npos);
  tunekit::vision::set_max_image_pixels(tunekit::vision::kDefaultMaxImagePixels);  // the CLI run above lowered it
  CHECK_NOTHROW(decode_image(pgm, "two_mp.pgm"));
  CHECK_THROWS_AS(tunekit::vision::set_max_image_pixels(0), tunekit::InputError);
}

TEST_CASE("one wild accelerometer sample does not erase the resonance", "[safety]") {
  tunekit::test::SweepSpec spec;
  spec.f_start_hz = 20;
  spec.f_end_hz = 80;
  spec.hz_per_sec = 4;
  spec.noise_mm_s2 = 50;
  auto rec = tunekit::test::synth_sweep({{45.0, 0.05, 1.0}}, spec);
  // A y-axis test: the mode shows on accel_y.
  std::swap(rec.ax, rec.ay);
  const std::size_t wild_row = rec.t.size() / 3;
  rec.ay[wild_row] = 0;
  // The wild value as a logger writes it: "1e200" in the accel_y field of that row.
  auto with_wild = [](std::string csv, std::size_t row) {
    std::size_t pos = 0;
    for (std::size_t k = 0; k <= row; ++k) pos = csv.find('\n', pos) + 1;  // start of data row `row`
    const auto c1 = csv.find(',', pos), c2 = csv.find(',', c1 + 1), c3 = csv.find(',', c2 + 1);
    return csv.replace(c2 + 1, c3 - c2 - 1, "1e200");
  };
  const auto dir = scratch_dir("hostile_wild_sample");
  const auto path = write_file(dir, "raw_data_y_wild.csv", with_wild(tunekit::test::to_klipper_csv(rec), wild_row));
  const auto r = run_cli({"resonance", path, "--json"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto j = nlohmann::json::parse(r.out);
  const auto& modes = j["results"]["axes"]["y"]["modes"];
  REQUIRE(modes.size() >= 1);
  CHECK(modes[0]["freq_hz"].get<double>() == Approx(45).epsilon(0.02));
  // The replaced sample is reported at its line (the header is line 1, data row k on line k + 2).
  const std::string where = path + ":" + std::to_string(wild_row + 2) + ": accel_y = 1e+200";
  CHECK(r.err.find(where) != std::string::npos);
  // Many wild samples: the record is refused (exit 2), never an empty result with exit 0.
  std::string corrupt = tunekit::test::to_klipper_csv(rec);
  for (std::size_t i = 0; i < rec.t.size(); i += 100) corrupt = with_wild(corrupt, i);
  const auto bad = write_file(dir, "raw_data_y_corrupt.csv", corrupt);
  const auto rb = run_cli({"resonance", bad});
  CHECK(rb.code == 2);
  CHECK(rb.err.find("beyond any accelerometer's range") != std::string::npos);
}

TEST_CASE("CSV files with a UTF-16 or a doubled byte-order mark are read", "[safety]") {
  const std::string text = "time,force (N)\n0,1.5\n1,2.5\n2,3.5\n";
  auto utf16 = [&](bool little) {
    std::string out = little ? std::string("\xFF\xFE", 2) : std::string("\xFE\xFF", 2);
    for (char c : text) {
      if (little) out += std::string{c, '\0'};
      else out += std::string{'\0', c};
    }
    return out;
  };
  for (const std::string& bytes : {utf16(true), utf16(false), "\xEF\xBB\xBF\xEF\xBB\xBF" + text}) {
    const auto t = tunekit::formats::parse_csv(bytes, "bom.csv", {{"time", "force"}, "time"});
    CHECK(t.rows == 3);
    CHECK(t.column("force").values.back() == 3.5);
    CHECK(t.column("force").unit == "N");
  }
  const auto dir = scratch_dir("hostile_bom");
  const auto path = write_file(dir, "utf16.csv", utf16(true));
  const auto r = run_cli({"inspect", path, "--time", "time", "--json"});
  INFO(r.err);
  CHECK(r.code == 0);
  CHECK(r.err.find("\xEF\xBF\xBD") == std::string::npos);  // no replacement characters
  // An odd byte count after a UTF-16 mark is refused clearly.
  CHECK_THROWS_AS(tunekit::formats::parse_csv(utf16(true) + "x", "odd.csv"), tunekit::InputError);
}
