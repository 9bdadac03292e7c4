// A rendered photo of Holtrup's (2019) sine-modulated ring goes through
// `tunekit linewidth` (profile CSV against time, set-point width from eq. 4.3) and then
// `tunekit freq` (sine dwell) to the gain and phase lag that were rendered. The photos carry
// blur, noise, strong vignetting and uneven lighting, so the detector must not take the dark
// corners or the lighting gradient for lines.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "synthetic_render.hpp"
#include "test_support.hpp"
#include "tunekit/vision/image_io.hpp"
#include "tunekit/vision/width_to_dynamics.hpp"

using namespace tunekit;
namespace rd = tunekit::test::render;
using tunekit::test::run_cli;
namespace fs = std::filesystem;

namespace {

struct RingCase {
  const char* name;
  double gain;        // rendered width amplitude / set-point amplitude
  double lag_deg;     // rendered phase lag of the width behind the set-point (deg)
  double start_deg;   // view angle of theta = 0 (deg, counterclockwise from +x)
  bool dark_line;     // dark filament on a light bed, or light on dark
  double vignetting;  // relative falloff at the corners
  double gradient;    // relative lighting change left to right
  unsigned seed;
};

std::string fmtnum(double v) { return fmt::format("{:.9g}", v); }

}  // namespace

TEST_CASE("rendered sine-modulated ring photo -> tunekit linewidth -> tunekit freq gives the rendered gain and phase") {
  // The ring print (Holtrup 2019, section 4.3.3): N sines per rotation, feeder offset amplitude A,
  // print speed v, ring radius R, rod radius r_rod, layer height h, mean set-point width w_g.
  vision::RingSine ring;
  ring.n_sines = 3;
  ring.amplitude_mm = 0.06;
  ring.speed_mm_s = 10.0;
  ring.radius_mm = 25.0;
  ring.rod_radius_mm = 1.5;
  ring.layer_height_mm = 0.2;
  ring.width_gcode_mm = 1.2;
  const double ppm = 10.0;  // px/mm
  const double f_hz = vision::ring_frequency_hz(ring);
  const double a_sp = vision::ring_setpoint_amplitude_mm(ring);  // about 0.24 mm
  REQUIRE(a_sp > 0.1);

  const RingCase cases[] = {
      {"dark ring, strong vignetting (70 % at the corners)", 0.8, 25.0, 30.0, true, 0.7, 0.0, 3},
      {"light ring, vignetting and a lighting gradient", 0.6, 60.0, 200.0, false, 0.5, 0.6, 4},
  };
  for (const auto& c : cases) {
    INFO(c.name);
    const auto dir = test::scratch_dir(fmt::format("lw_ring_freq_{}", c.seed));
    // The photo: width(theta) = w_g - gain a_sp cos(N theta - lag) with theta = phi - start the
    // angle travelled counterclockwise from the start, so that in time (theta = v t / R) the
    // width lags eq. 4.3's set-point w_g - a_sp cos(N v t / R) by `lag`.
    const double start = c.start_deg * M_PI / 180.0, lag = c.lag_deg * M_PI / 180.0;
    const double w = 640, h = 640, cx = 0.5 * w + 1.3, cy = 0.5 * h - 0.8;
    const auto cov = rd::coverage(
        static_cast<int>(w), static_cast<int>(h), rd::ring(cx, cy, ring.radius_mm * ppm, [&](double phi) {
          const double width_mm = ring.width_gcode_mm - c.gain * a_sp * std::cos(ring.n_sines * (phi - start) - lag);
          return width_mm * ppm;
        }));
    rd::Photo ph;
    ph.bed = c.dark_line ? 205 : 50;
    ph.line = c.dark_line ? 70 : 185;
    ph.blur_px = 1.2;
    ph.noise = 2.0;
    ph.vignetting = c.vignetting;
    ph.gradient = c.gradient;
    ph.seed = c.seed;
    const std::string img = (fs::path(dir) / "ring.png").string();
    vision::write_png(img, rd::photograph(cov, ph));
    const std::string csv = (fs::path(dir) / "ring.csv").string();

    const auto lw = run_cli({"linewidth",
                             img,
                             "--px-per-mm",
                             fmtnum(ppm),
                             "--json",
                             "--overlay",
                             dir + "/ov",
                             "--speed-mm-s",
                             fmtnum(ring.speed_mm_s),
                             "--ring-sines",
                             std::to_string(ring.n_sines),
                             "--ring-amplitude-mm",
                             fmtnum(ring.amplitude_mm),
                             "--ring-radius-mm",
                             fmtnum(ring.radius_mm),
                             "--rod-radius-mm",
                             fmtnum(ring.rod_radius_mm),
                             "--layer-height-mm",
                             fmtnum(ring.layer_height_mm),
                             "--setpoint-width-mm",
                             fmtnum(ring.width_gcode_mm),
                             "--ring-start-deg",
                             fmtnum(c.start_deg),
                             "--profile-csv",
                             csv});
    INFO(lw.err);
    REQUIRE(lw.code == 0);
    const auto jl = nlohmann::json::parse(lw.out);
    const auto& lines = jl["results"]["lines"];
    REQUIRE(lines.size() == 1);  // the ring only: no border "lines" from vignetting or lighting
    CHECK(lines[0]["closed"] == true);
    CHECK(lines[0]["touches_frame"] == false);
    CHECK(lines[0]["width_mm"]["mean"].get<double>() == Approx(ring.width_gcode_mm).margin(0.01));
    CHECK(jl["results"]["images"][0]["polarity"] == (c.dark_line ? "dark" : "light"));
    const auto& map = jl["results"]["profile_csv"];
    CHECK(map["frequency_hz"].get<double>() == Approx(f_hz).epsilon(1e-5));
    CHECK(map["setpoint_amplitude_mm"].get<double>() == Approx(a_sp).epsilon(1e-5));
    // One sample per px of centreline, from theta = 2.5 rad (the ring's start, where a printed
    // ring is still filling, is left out) to 0.05 rad short of a full turn: 59 % of the turn.
    CHECK(map["skipped_start_deg"].get<double>() == Approx(2.5 * 180 / M_PI));
    CHECK(map["rows"].get<double>() > 0.57 * 2 * M_PI * ring.radius_mm * ppm);
    CHECK(fs::exists(dir + "/ov/ring_overlay.png"));
    // linewidth's own ring measurement (the one calibrate's camera path makes): the same answer.
    const auto& rr = jl["results"]["ring"];
    CHECK(rr["freq_hz"].get<double>() == Approx(f_hz).epsilon(1e-5));
    CHECK(std::abs(rr["gain"].get<double>() / c.gain - 1) <= 0.03);
    CHECK(std::abs(-rr["phase_deg"].get<double>() - c.lag_deg) <= 3.0);

    const auto fr = run_cli({"freq", csv, "--time", "time", "--output", "width", "--input", "setpoint_width",
                             "--freq-hz", fmtnum(f_hz), "--json"});
    INFO(fr.err);
    REQUIRE(fr.code == 0);
    const auto jf = nlohmann::json::parse(fr.out);
    const auto& sd = jf["results"]["sine_dwell"];
    const double gain = sd["gain"]["value"].get<double>();
    const double lag_deg = sd["phase_lag_deg"]["value"].get<double>();
    INFO(
        fmt::format("gain {:.4f} (rendered {}), phase lag {:.3f} deg (rendered {})", gain, c.gain, lag_deg, c.lag_deg));
    CHECK(std::abs(gain / c.gain - 1) <= 0.03);
    CHECK(std::abs(lag_deg - c.lag_deg) <= 3.0);
    // The reported 95 % intervals are honest about it.
    CHECK(sd["gain"]["ci95"][0].get<double>() <= c.gain * 1.03);
    CHECK(sd["gain"]["ci95"][1].get<double>() >= c.gain * 0.97);
  }
}
