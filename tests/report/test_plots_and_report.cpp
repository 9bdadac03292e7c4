// Plots (PLplot, PNG) and the self-contained HTML report.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "test_support.hpp"
#include "tunekit/cli/report.hpp"
#include "tunekit/ident/csv.hpp"
#include "tunekit/ident/image_io.hpp"

using namespace tunekit::cli;

namespace {

std::vector<double> linspace(double a, double b, int n) {
  std::vector<double> v(n);
  for (int i = 0; i < n; ++i) v[i] = a + (b - a) * i / (n - 1);
  return v;
}

nlohmann::json sample_plotdata() {
  nlohmann::json pd;
  auto t = linspace(0, 4, 400);
  std::vector<double> u, y, yf;
  for (double ti : t) {
    u.push_back(ti < 1 ? 1 : 2);
    const double r = ti < 1.04 ? 0 : 1 - std::exp(-(ti - 1.04) / 0.45);
    yf.push_back(0.9 + 0.9 * r);
    y.push_back(yf.back() + 0.01 * std::sin(37 * ti));
  }
  pd["step"] = {{"t_s", t}, {"u", u}, {"y", y}, {"y_fit", yf}, {"u_label", "feed (mm/s)"}, {"y_label", "force (N)"}};
  auto f = linspace(0.05, 5, 60);
  std::vector<double> mag, ph, coh;
  for (double fi : f) {
    const double w = 2 * M_PI * fi;
    mag.push_back(20 * std::log10(0.8865 / std::hypot(1, 0.45 * w)));
    ph.push_back(-std::atan(0.45 * w) * 180 / M_PI - 0.04 * w * 180 / M_PI);
    coh.push_back(0.95);
  }
  pd["bode"] = {{"freq_hz", f}, {"mag_db", mag}, {"phase_deg", ph}, {"coherence", coh},
                {"model", {{"freq_hz", f}, {"mag_db", mag}, {"phase_deg", ph}}}};
  auto fp = linspace(5, 200, 300);
  std::vector<double> psd, resp;
  for (double fi : fp) {
    psd.push_back(1e4 / (std::pow(1 - (fi / 44) * (fi / 44), 2) + std::pow(0.1 * fi / 44, 2)));
    resp.push_back(std::abs(std::cos(M_PI * fi / 88)));
  }
  pd["psd_x"] = {{"freq_hz", fp}, {"psd", psd}, {"modes", {{{"freq_hz", 44.0}}}},
                 {"shapers", {{{"type", "zv"}, {"freq_hz", fp}, {"response", resp}}}}};
  auto g = linspace(1, 4, 30);
  std::vector<double> sr, eta;
  for (double gi : g) {
    sr.push_back(std::pow(10, gi));
    eta.push_back(1000 / (1 + std::pow(sr.back() / 100, 0.6)));
  }
  pd["viscosity"] = {{"series", {{{"temperature_K", 673}, {"shear_rate_1_s", sr}, {"viscosity_Pa_s", eta},
                                  {"fit_shear_rate_1_s", sr}, {"fit_viscosity_Pa_s", eta}}}}};
  auto s = linspace(0, 188, 500);
  std::vector<double> w, sp;
  for (double si : s) {
    w.push_back(0.7 + 0.2 * std::sin(si / 5));
    sp.push_back(0.66 + 0.78 * std::sin(si / 5 + 0.3));
  }
  pd["linewidth"] = {{"s_mm", s}, {"width_mm", w}, {"setpoint_mm", sp}};
  return pd;
}

// Counts pixels that are not (near) white: a drawn plot has many.
int drawn_pixels(const cv::Mat& img) {
  int n = 0;
  for (int r = 0; r < img.rows; ++r)
    for (int c = 0; c < img.cols; ++c) {
      const auto p = img.at<cv::Vec3b>(r, c);
      if (p[0] < 200 || p[1] < 200 || p[2] < 200) ++n;
    }
  return n;
}

}  // namespace

TEST_CASE("each plot type renders a non-empty PNG of the expected size") {
  const auto dir = tunekit::test::scratch_dir("plots");
  const auto images = render_report_plots(dir, sample_plotdata());
  REQUIRE(images.size() == 5);
  const std::map<std::string, std::pair<int, int>> expected{{"step", {960, 760}},      {"bode", {960, 760}},
                                                            {"psd_x", {960, 720}},     {"viscosity", {960, 640}},
                                                            {"linewidth", {960, 420}}};
  for (const auto& img : images) {
    INFO(img.id);
    const cv::Mat m = tunekit::ident::read_image(img.png_path, tunekit::ident::ImageColor::bgr);
    REQUIRE_FALSE(m.empty());
    CHECK(m.cols == expected.at(img.id).first);
    CHECK(m.rows == expected.at(img.id).second);
    CHECK(drawn_pixels(m) > m.rows * m.cols / 100);  // axes, labels and curves
  }
}

TEST_CASE("a figure without data is refused") {
  Figure f;
  Panel empty;
  empty.title = "empty";
  f.panels.push_back(empty);
  CHECK_THROWS(render_png(f, tunekit::test::scratch_dir("plots_empty") + "/e.png"));
}

TEST_CASE("the report embeds every plot and its summary numbers equal results.json") {
  const auto dir = tunekit::test::scratch_dir("report_run");
  nlohmann::json env = {{"schema_version", 1}, {"command", "calibrate"}, {"tool", {{"version", "test"}}}};
  env["results"] = {{"machine", "test machine"},
                    {"compensators", {{"pressure_advance", {{"k_s", 0.4512345678}, {"smooth_time_s", 0.04}}}}},
                    {"axes", {{"x", {{"modes", {{{"freq_hz", 44.123456}, {"zeta", 0.0712}}}}}}}},
                    {"summary", {{{"label", "pressure advance K"}, {"path", "compensators.pressure_advance.k_s"}, {"unit", "s"}},
                                 {{"label", "x resonance"}, {"path", "axes.x.modes[0].freq_hz"}, {"unit", "Hz"}},
                                 {{"label", "x damping"}, {"path", "axes.x.modes[0].zeta"}, {"unit", "1"}}}},
                    {"config_diff", "--- a\n+++ b\n-pressure_advance = 0\n+pressure_advance = 0.451\n"}};
  std::ofstream(dir + "/results.json") << env.dump(2);
  auto pd = sample_plotdata();
  {  // a stand-in for the line-width overlay photo: any PNG
    const auto shots = render_report_plots(tunekit::test::scratch_dir("report_overlay"), pd);
    std::filesystem::copy_file(shots.back().png_path, dir + "/overlay.png");
  }
  pd["linewidth"]["overlay_png"] = "overlay.png";
  std::ofstream(dir + "/plotdata.json") << pd.dump();
  const auto r = tunekit::test::run_cli({"report", dir});
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(r.out == dir + "/report.html\n");
  const std::string html = tunekit::ident::read_file_bytes(dir + "/report.html");

  // Self-contained: no external references.
  CHECK(html.find("src=\"http") == std::string::npos);
  CHECK(html.find("<script") == std::string::npos);
  for (const char* id : {"step", "bode", "psd_x", "viscosity", "linewidth", "linewidth_overlay"}) {
    INFO(id);
    CHECK(tunekit::test::embedded_png_base64_length(html, id) > 1000);
  }
  // Summary: every cell's exact value and displayed value come from results.json.
  int cells = 0;
  for (const auto& c : tunekit::test::summary_cells(html)) {
    const auto* v = json_at(env["results"], c.path);
    REQUIRE(v != nullptr);
    CHECK(std::stod(c.value) == v->get<double>());
    CHECK(c.display == display_number(v->get<double>()));
    ++cells;
  }
  CHECK(cells == 3);
  CHECK(html.find("+pressure_advance = 0.451") != std::string::npos);
}

TEST_CASE("report on a directory without results.json is an input error") {
  const auto dir = tunekit::test::scratch_dir("report_empty");
  const auto r = tunekit::test::run_cli({"report", dir});
  CHECK(r.code == 2);
  CHECK(r.err.find("results.json: cannot open") != std::string::npos);
}
