// The report's step figure: the measured record, the whole-record model's simulated output over
// all of it and each step's fit over its own step, with a legend; without the model it shows the
// record and the step fits and says why the model is missing.
//
// PLplot's cairo SVG device writes every stroke as a <path> in its colour (and text as glyph
// outlines), so a series is found by its palette colour: its points are the coordinate pairs of
// the paths stroked in that colour.
#include <unistd.h>

#include <catch2/catch.hpp>

#include <algorithm>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>

#include <nlohmann/json.hpp>

#include "test_support.hpp"
#include "tunekit/calibration/presentation/report.hpp"
#include "tunekit/core/file_bytes.hpp"

using namespace tunekit::calibration;

namespace {

// A palette colour (plots.cpp) as cairo writes it: rgb(r%,g%,b%) with six decimals.
std::string svg_rgb(int r, int g, int b) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "rgb(%f%%,%f%%,%f%%)", r / 2.55, g / 2.55, b / 2.55);
  return buf;
}
const std::string kMeasured = svg_rgb(31, 119, 180);  // palette 1
const std::string kStepFits = svg_rgb(214, 39, 40);   // palette 2
const std::string kModel = svg_rgb(148, 103, 189);    // palette 5 (kWholeRecordModelColor)

// Coordinate pairs of the paths stroked in each colour.
std::map<std::string, std::size_t> points_by_stroke(const std::string& svg) {
  std::map<std::string, std::size_t> out;
  for (auto p = svg.find("<path"); p != std::string::npos; p = svg.find("<path", p + 1)) {
    const std::string tag = svg.substr(p, svg.find('>', p) - p);
    const auto s = tag.find("stroke:");
    const auto d = tag.find(" d=\"");
    if (s == std::string::npos || d == std::string::npos) continue;
    const std::string color = tag.substr(s + 7, tag.find(';', s) - s - 7);
    const std::string path = tag.substr(d + 4, tag.find('"', d + 4) - d - 4);
    std::size_t numbers = 0;
    bool in_number = false;
    for (char c : path) {
      const bool digit = (c >= '0' && c <= '9') || c == '.' || c == '-' || c == 'e';
      if (digit && !in_number) ++numbers;
      in_number = digit;
    }
    out[color] += numbers / 2;
  }
  return out;
}

std::vector<double> figure_time_grid(double a, double b, int n) {
  std::vector<double> v(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) v[static_cast<std::size_t>(i)] = a + (b - a) * i / (n - 1);
  return v;
}

// A staircase record with a model over all of it and step fits over each step's window (null
// elsewhere, as step_plotdata writes them).
nlohmann::json step_data(bool with_model) {
  const auto t = figure_time_grid(0, 12, 600);
  nlohmann::json u = nlohmann::json::array(), y = nlohmann::json::array(), yf = nlohmann::json::array(),
                 ym = nlohmann::json::array();
  for (double ti : t) {
    const double level = ti < 2 ? 4 : ti < 6 ? 8 : ti < 10 ? 5 : 9;
    u.push_back(level);
    const double lagged = level + 0.3 * std::sin(3 * ti);
    ym.push_back(lagged);
    y.push_back(lagged + 0.05 * std::sin(41 * ti));
    const bool in_step = (ti > 2.1 && ti < 5.5) || (ti > 6.1 && ti < 9.5);
    yf.push_back(in_step ? nlohmann::json(lagged + 0.02) : nlohmann::json(nullptr));
  }
  nlohmann::json d{{"t_s", t}, {"u", u}, {"y", y}, {"y_fit", yf}, {"u_label", "flow (mm^3/s)"}, {"y_label", "flow"}};
  if (with_model) {
    d["y_model"] = ym;
    d["model_label"] = "whole-record model (b = -0.45)";
  } else {
    d["model_missing"] = "the input goes below zero";
  }
  return d;
}

std::string step_svg(const std::string& dir, const nlohmann::json& step, std::string& caption) {
  const auto images = render_report_plots(dir, plots_from_json({{"step", step}}));
  REQUIRE(images.size() == 1);
  REQUIRE(images[0].id == "step");
  caption = images[0].caption;
  const std::string html = build_report_html(CalibrationRecord{}, images);
  CHECK(html.find("<figure id=\"plot-step\">") != std::string::npos);
  CHECK(html.find(caption) != std::string::npos);
  // The SVG text is kept from rendering: the file holds the same bytes.
  CHECK(images[0].bytes == tunekit::read_file_bytes(images[0].path));
  return images[0].bytes;
}

}  // namespace

TEST_CASE("the step figure draws the record, the whole-record model and the step fits, each in the legend") {
  std::string caption;
  const auto svg = step_svg(tunekit::test::scratch_dir("whole_record_figure"), step_data(true), caption);
  const auto points = points_by_stroke(svg);
  INFO("measured " << points.count(kMeasured) << ", step fits " << points.count(kStepFits) << ", model "
                   << points.count(kModel));
  // Each series is a curve of hundreds of points (a legend sample is two); the step fits' curve
  // is drawn in its two windows only.
  REQUIRE(points.count(kMeasured) == 1);
  REQUIRE(points.count(kStepFits) == 1);
  REQUIRE(points.count(kModel) == 1);
  CHECK(points.at(kMeasured) > 500);
  CHECK(points.at(kModel) > 2 * 500);  // the model and its residuals
  CHECK(points.at(kStepFits) > 300);
  CHECK(points.at(kStepFits) < 600);
  // The legends: white boxes (the input's and the output's) with a sample line of each series.
  const std::string legend_box = "<path style=\"fill-rule:nonzero;fill:rgb(100%,100%,100%)";
  std::size_t legends = 0;
  for (auto p = svg.find(legend_box); p != std::string::npos; p = svg.find(legend_box, p + 1)) ++legends;
  CHECK(legends >= 2);
  CHECK(caption.find("whole-record model") != std::string::npos);
  CHECK(caption.find("not fitted") == std::string::npos);
}

TEST_CASE("without the whole-record model the step figure shows the record and the step fits and says why") {
  std::string caption;
  const auto svg = step_svg(tunekit::test::scratch_dir("whole_record_figure_missing"), step_data(false), caption);
  const auto points = points_by_stroke(svg);
  CHECK(points.count(kMeasured) == 1);
  CHECK(points.count(kStepFits) == 1);
  CHECK(points.count(kModel) == 0);
  CHECK(caption.find("whole-record model not fitted: the input goes below zero") != std::string::npos);
  CHECK(step_model_note(plots_from_json({{"step", step_data(false)}}).step.value()) ==
        "whole-record model not fitted: the input goes below zero");
  CHECK(step_model_note(plots_from_json({{"step", step_data(true)}}).step.value()).empty());
}

TEST_CASE("calibrate's report: the step figure holds the whole-record model fitted to the flow sweep") {
  // The shared default calibration: this test only reads what it wrote.
  const auto& run = tunekit::test::default_calibration();
  const std::string& dir = run.dir;
  INFO(run.cli.err);
  REQUIRE(run.cli.code == 0);
  const auto pd = tunekit::test::read_json(dir + "/plotdata.json").at("step");
  REQUIRE(pd.contains("y_model"));
  const auto& t = pd.at("t_s");
  const auto& ym = pd.at("y_model");
  REQUIRE(ym.size() == t.size());
  // The model is fitted from the first step's window on (before it the liquefier fills from
  // rest, 3 s of the 45 s record): from there on every plotted sample has the model's value, none
  // before.
  const std::size_t first = static_cast<std::size_t>(
      std::find_if(ym.begin(), ym.end(), [](const nlohmann::json& v) { return v.is_number(); }) - ym.begin());
  std::size_t finite = 0;
  for (const auto& v : ym) finite += v.is_number();
  CHECK(first > 0);
  CHECK(first < ym.size() / 10);
  CHECK(finite == ym.size() - first);
  // The model follows the record: its residuals are small against the output's range.
  const auto& y = pd.at("y");
  double lo = 1e300, hi = -1e300, ss = 0;
  for (std::size_t i = first; i < y.size(); ++i) {
    lo = std::min(lo, y[i].get<double>());
    hi = std::max(hi, y[i].get<double>());
    ss += std::pow(y[i].get<double>() - ym[i].get<double>(), 2);
  }
  const double rms = std::sqrt(ss / static_cast<double>(y.size() - first));
  INFO("model rms " << rms << " over an output range " << hi - lo);
  CHECK(rms < 0.05 * (hi - lo));
  const std::string html = tunekit::read_file_bytes(dir + "/report.html");
  CHECK(tunekit::test::embedded_image_base64_length(html, "step") > 2000);
  CHECK(html.find("the whole-record model over all of it") != std::string::npos);
  const auto points = points_by_stroke(tunekit::read_file_bytes(dir + "/plots/step.svg"));
  REQUIRE(points.count(kModel) == 1);
  CHECK(points.at(kModel) > 1000);
}

TEST_CASE("tunekit step --plot draws the same figure: the record, the whole-record model and the step fits") {
  const std::string dir = tunekit::test::scratch_dir("whole_record_step_plot");
  const std::string csv = tunekit::test::dataset("liquefier/synthetic_steps.csv");
  const auto r = tunekit::test::run_cli({"step", csv, "--time", "time", "--input", "feed", "--output", "force",
                                         "--step-at", "first", "--plot", dir + "/step.svg"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(r.out.find("whole record: tau = a u^b") != std::string::npos);
  const auto points = points_by_stroke(tunekit::read_file_bytes(dir + "/step.svg"));
  REQUIRE(points.count(kMeasured) == 1);
  REQUIRE(points.count(kModel) == 1);
  REQUIRE(points.count(kStepFits) == 1);
  CHECK(points.at(kMeasured) > 500);
  CHECK(points.at(kModel) > 2 * 500);
  CHECK(points.at(kStepFits) > 100);
  // A PNG on request; the options it needs are checked before anything is fitted.
  CHECK(tunekit::test::run_cli(
            {"step", csv, "--time", "time", "--input", "feed", "--output", "force", "--plot", dir + "/step.png"})
            .code == 0);
  CHECK(std::filesystem::file_size(dir + "/step.png") > 1000);
  const auto no_input = tunekit::test::run_cli(
      {"step", csv, "--time", "time", "--output", "force", "--step-size", "1", "--plot", dir + "/x.svg"});
  CHECK(no_input.code == 2);
  CHECK(no_input.err.find("tunekit: error: --plot draws the record against its input") != std::string::npos);
  const auto pdf = tunekit::test::run_cli(
      {"step", csv, "--time", "time", "--input", "feed", "--output", "force", "--plot", dir + "/x.pdf"});
  CHECK(pdf.code == 2);
  CHECK(!std::filesystem::exists(dir + "/x.svg"));
  // A place the figure cannot be written: one plain error, not the plotting library's abort.
  const auto unwritable = tunekit::test::run_cli(
      {"step", csv, "--time", "time", "--input", "feed", "--output", "force", "--plot", "/proc/x.svg"});
  CHECK(unwritable.code == 2);
  CHECK(unwritable.err.find("tunekit: error: /proc/x.svg: cannot write the figure there") != std::string::npos);
  CHECK(unwritable.err.find("PLPLOT") == std::string::npos);
}
