// Plots (PLplot: SVG for the report, PNG on request) and the self-contained HTML report.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "test_support.hpp"
#include "tunekit/calibration/presentation/report.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/calibration/results/json_access.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/vision/image_io.hpp"
#include "tunekit/core/file_bytes.hpp"

using namespace tunekit::calibration;

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
  pd["bode"] = {{"freq_hz", f},
                {"mag_db", mag},
                {"phase_deg", ph},
                {"coherence", coh},
                {"model", {{"freq_hz", f}, {"mag_db", mag}, {"phase_deg", ph}}}};
  auto fp = linspace(5, 200, 300);
  std::vector<double> psd, resp;
  for (double fi : fp) {
    psd.push_back(1e4 / (std::pow(1 - (fi / 44) * (fi / 44), 2) + std::pow(0.1 * fi / 44, 2)));
    resp.push_back(std::abs(std::cos(M_PI * fi / 88)));
  }
  pd["psd_x"] = {{"freq_hz", fp},
                 {"psd", psd},
                 {"modes", {{{"freq_hz", 44.0}}}},
                 {"shapers", {{{"type", "zv"}, {"freq_hz", fp}, {"response", resp}}}}};
  auto g = linspace(1, 4, 30);
  std::vector<double> sr, eta;
  for (double gi : g) {
    sr.push_back(std::pow(10, gi));
    eta.push_back(1000 / (1 + std::pow(sr.back() / 100, 0.6)));
  }
  pd["viscosity"] = {{"series",
                      {{{"temperature_K", 673},
                        {"shear_rate_1_s", sr},
                        {"viscosity_Pa_s", eta},
                        {"fit_shear_rate_1_s", sr},
                        {"fit_viscosity_Pa_s", eta}}}}};
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

TEST_CASE("each plot type renders an SVG of the expected size with its curves drawn") {
  const auto dir = tunekit::test::scratch_dir("plots");
  const auto images = render_report_plots(dir, plots_from_json(sample_plotdata()));
  REQUIRE(images.size() == 5);
  const std::map<std::string, std::pair<int, int>> expected{{"step", {960, 760}},
                                                            {"bode", {960, 760}},
                                                            {"psd_x", {960, 720}},
                                                            {"viscosity", {960, 640}},
                                                            {"linewidth", {960, 420}}};
  for (const auto& img : images) {
    INFO(img.id);
    CHECK(std::filesystem::path(img.path).extension() == ".svg");
    const std::string svg = tunekit::read_file_bytes(img.path);
    REQUIRE(svg.find("<svg") != std::string::npos);
    const auto [w, h] = expected.at(img.id);
    CHECK(svg.find("width=\"" + std::to_string(w) + "pt\" height=\"" + std::to_string(h) + "pt\"") !=
          std::string::npos);
    std::size_t paths = 0;
    for (auto pos = svg.find("<path"); pos != std::string::npos; pos = svg.find("<path", pos + 1)) ++paths;
    CHECK(paths > 100);  // axes, glyphs of the labels, curves
  }
}

TEST_CASE("a PNG rendering of a figure has exactly its pixel size and is drawn") {
  const auto dir = tunekit::test::scratch_dir("plots_png");
  const Figure f = step_figure(plots_from_json(sample_plotdata()).step.value());
  render_png(f, dir + "/step.png");
  const cv::Mat m = tunekit::vision::read_image(dir + "/step.png", tunekit::vision::ImageColor::bgr);
  REQUIRE_FALSE(m.empty());
  CHECK(m.cols == f.width_px);
  CHECK(m.rows == f.height_px);
  CHECK(drawn_pixels(m) > m.rows * m.cols / 100);
  CHECK_THROWS_AS(render_png(f, dir + "/step.svg"), tunekit::InputError);
  CHECK_THROWS_AS(render_figure(f, dir + "/step.gif"), tunekit::InputError);
}

TEST_CASE("log axes are labelled at decades and, over short spans, at 2x and 5x") {
  // A Bode axis from 0.098 Hz to 4.98 Hz: one decade mark alone would leave "1" as its only number.
  const auto t = log_axis_ticks(std::log10(0.098), std::log10(4.98));
  const std::vector<double> want{0.1, 0.2, 0.5, 1, 2};  // 5 lies beyond 4.98
  REQUIRE(t.size() == want.size());
  for (std::size_t i = 0; i < want.size(); ++i) CHECK(t[i] == Approx(want[i]));
  // Over more than three decades only the decades.
  const auto d = log_axis_ticks(0.5, 4.2);
  const std::vector<double> decades{10, 100, 1000, 10000};
  REQUIRE(d.size() == decades.size());
  for (std::size_t i = 0; i < decades.size(); ++i) CHECK(d[i] == Approx(decades[i]));
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
  env["results"] = {
      {"machine", "test machine"},
      {"compensators", {{"pressure_advance", {{"k_s", 0.4512345678}, {"smooth_time_s", 0.04}}}}},
      {"axes", {{"x", {{"modes", {{{"freq_hz", 44.123456}, {"freq_ci95", {43.9, 44.35}}, {"zeta", 0.0712}}}}}}}},
      {"summary",
       {{{"label", "pressure advance K"},
         {"path", "compensators.pressure_advance.k_s"},
         {"unit", "s"},
         {"basis", "designed"}},
        {{"label", "x resonance"},
         {"path", "axes.x.modes[0].freq_hz"},
         {"unit", "Hz"},
         {"ci_path", "axes.x.modes[0].freq_ci95"}},
        {{"label", "x damping"}, {"path", "axes.x.modes[0].zeta"}, {"unit", "1"}}}},
      {"config_diff", "--- a\n+++ b\n-pressure_advance = 0\n+pressure_advance = 0.451\n"}};
  std::ofstream(dir + "/results.json") << env.dump(2);
  auto pd = sample_plotdata();
  {  // a stand-in for the line-width overlay photo: any PNG
    render_png(linewidth_figure(plots_from_json(pd).linewidth.value()), dir + "/overlay.png");
  }
  pd["linewidth"]["overlay_png"] = "overlay.png";
  std::ofstream(dir + "/plotdata.json") << pd.dump();
  const auto r = tunekit::test::run_cli({"report", dir});
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(r.out == dir + "/report.html\n");
  const std::string html = tunekit::read_file_bytes(dir + "/report.html");

  // Self-contained: no external references.
  CHECK(html.find("src=\"http") == std::string::npos);
  CHECK(html.find("<script") == std::string::npos);
  for (const char* id : {"step", "bode", "psd_x", "viscosity", "linewidth"}) {
    INFO(id);
    CHECK(tunekit::test::embedded_image_base64_length(html, id) > 1000);
    CHECK(tunekit::test::embedded_png_base64_length(html, id) == 0);  // plots are SVG
  }
  CHECK(tunekit::test::embedded_png_base64_length(html, "linewidth_overlay") > 1000);  // the photo stays a PNG
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
  // Intervals: [lo, hi] where there is one, the basis where the row gives it, n/a otherwise.
  CHECK(html.find("<td class=\"ci\" data-path=\"axes.x.modes[0].freq_ci95\">[43.9, 44.35]</td>") != std::string::npos);
  CHECK(html.find("<td class=\"ci\">designed</td>") != std::string::npos);
  CHECK(html.find("<td class=\"ci\">n/a</td>") != std::string::npos);
  // Nothing may leave the file, and the plots are SVG.
  CHECK(html.find("<meta http-equiv=\"Content-Security-Policy\" content=\"default-src 'none'; img-src data:;") !=
        std::string::npos);
  CHECK(html.find("src=\"data:image/svg+xml;base64,") != std::string::npos);
}

TEST_CASE("every warning in the report carries a one-line what to do") {
  const auto dir = tunekit::test::scratch_dir("report_warnings");
  nlohmann::json env = {{"schema_version", 1}, {"command", "calibrate"}, {"tool", {{"version", "test"}}}};
  env["warnings"] = {"steady-state gain 0.93 differs from 1: the delivered flow is off by that factor",
                     "something no table knows about"};
  env["results"] = {{"summary", nlohmann::json::array()}, {"notes", {"dead time theta = 0.04 s is not cancelled"}}};
  const std::string html = build_report_html(record_from_json(env, {}, "results.json"), {});
  CHECK(html.find("differs from 1: the delivered flow is off by that factor<br><span class=\"todo\">What to do: "
                  "calibrate the extrusion multiplier") != std::string::npos);
  CHECK(html.find("something no table knows about<br><span class=\"todo\">What to do: check the file") !=
        std::string::npos);
  CHECK(html.find("<ul id=\"notes\">\n<li>dead time theta = 0.04 s is not cancelled</li>") != std::string::npos);
}

TEST_CASE("report on a directory without results.json is an input error") {
  const auto dir = tunekit::test::scratch_dir("report_empty");
  const auto r = tunekit::test::run_cli({"report", dir});
  CHECK(r.code == 2);
  CHECK(r.err.find("results.json: cannot open") != std::string::npos);
}
