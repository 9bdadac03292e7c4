// tunekit nozzle: the command line of the command (options bound straight into the library's
// option structs, so --help shows the library's defaults); the work is done by the
// calibration library's compute function.

#include "tunekit/cli/command.hpp"
#include "tunekit/cli/analysis_commands.hpp"
#include "tunekit/cli/commands.hpp"
#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/analyses/nozzle_command.hpp"
#include "tunekit/cli/option_binding.hpp"
#include "tunekit/calibration/results/results_json.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/fitting/nozzle_pressure.hpp"
#include "tunekit/fitting/rheology_fit.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/ident/liquefier_prediction.hpp"
#include "tunekit/formats/rheology_data.hpp"
#include <cmath>
#include <fmt/format.h>
#include <memory>
#include <numbers>

namespace tunekit::cli {

using namespace calibration;

namespace {

struct NozzleCommand {
  NozzleOptions options;
  OutputOptions output;
};

/// `--name V` in display units (mm, degrees) setting an SI member as V * numerator / denominator
/// (the old arithmetic: mm * 1e-3, deg * pi / 180); the default shown is the member's current
/// value in display units.
CLI::Option* add_nozzle_si_option(CLI::App* sub, const std::string& names, double& si_target, double numerator,
                                  double denominator, const std::string& description) {
  auto* opt = sub->add_option_function<double>(
      names, [&si_target, numerator, denominator](double v) { si_target = v * numerator / denominator; }, description);
  opt->default_str(fmt::format("{:g}", nozzle_display_value(si_target, denominator / numerator)));
  return opt;
}

}  // namespace

CLI::App* add_nozzle_command(CLI::App& app, NozzleOptions& o, OutputOptions& output) {
  fitting::NozzleGeometry& g = o.prediction.geometry;
  auto* sub = app.add_subcommand("nozzle", "Nozzle pressure drop from rheology and geometry, and its inverse fit");
  add_choice_option<fitting::PressureModel>(
      sub, "--model", o.prediction.model,
      {{"boles", fitting::PressureModel::boles},
       {"bellini", fitting::PressureModel::bellini},
       {"power-law", fitting::PressureModel::power_law_capillary},
       {"hagen-poiseuille", fitting::PressureModel::hagen_poiseuille}},
      "Pressure-drop model: boles, bellini, power-law (capillary, Rabinowitsch) or hagen-poiseuille");
  sub->add_option("--K", o.K, "Power-law consistency K (Pa.s^n)");
  sub->add_option("--n", o.n, "Power-law index n (1)");
  sub->add_option("--mu", o.mu, "Newtonian viscosity (Pa.s)");
  sub->add_option("--material", o.material,
                  "Cross-WLF material of Holtrup 2019 (PEEK, ABS, ULTEM1010) or peek-power-law (eq. 5.10/5.11); needs "
                  "--temperature");
  sub->add_option("--rheology", o.rheology_json,
                  "A 'tunekit rheo --json' result file to take the viscosity model from");
  sub->add_option("-T,--temperature", o.temperature_degc, "Melt temperature (degC)");
  sub->add_option("--kelvin-offset", o.kelvin_offset,
                  "degC to K offset: 273.15 (SI) or 273 (Holtrup's (2019) code) (K)")
      ->capture_default_str();
  sub->add_option("-Q,--flow", o.flows_mm3_s, "Volumetric flow at the nozzle exit (mm3/s); repeatable");
  sub->add_option("--reference-flow", o.prediction.reference_flow_mm3_s, "Flow at which relative_tau is 1 (mm3/s)")
      ->capture_default_str();
  add_nozzle_si_option(sub, "--nozzle-d", g.d_m, 1e-3, 1, "Nozzle channel diameter d (mm)");
  add_nozzle_si_option(sub, "--nozzle-l", g.l_m, 1e-3, 1, "Nozzle land length l (mm)");
  add_nozzle_si_option(sub, "--cone-angle", g.cone_half_angle_rad, std::numbers::pi, 180.0,
                       "Cone half angle alpha (degrees; Bellini's beta is twice this)");
  add_nozzle_si_option(sub, "--entrance-D", g.D_m, 1e-3, 1, "Melt room / entrance diameter D (mm)");
  add_nozzle_si_option(sub, "--melt-length", g.melt_length_m, 1e-3, 1, "Bellini's melt room length L1 (mm)");
  sub->add_option("--fit", o.fit_file,
                  "Inverse fit: CSV with flow (mm3/s), pressure (MPa|Pa|bar) or force (N), temperature (degC|K)");
  sub->add_option("--piston-diameter", o.piston_diameter_mm,
                  "Diameter the feeder force acts on (mm), for a force column");
  sub->add_option("--max-rows", o.max_rows, "Most rows of the --fit file accepted (count); a longer file is refused")
      ->capture_default_str()
      ->check(CLI::Range(std::size_t{1}, std::size_t{100000000}));
  add_output_options(sub, output);
  sub->footer(
      "Defaults are Holtrup's (2019) regular nozzle (Table 5.3): d 0.6 mm, l 4 mm, alpha 30 deg, D 5 mm.\n"
      "Examples:\n"
      "  tunekit nozzle --K 10114 --n 0.51 --flow 20 --cone-angle 45          # appendix F: 12.16 MPa\n"
      "  tunekit nozzle --material peek-power-law -T 405 --flow 3             # sec. 5.2.3: 4.98 MPa\n"
      "  tunekit nozzle --material PEEK -T 405 --flow 1.5 --flow 3 --flow 6 --model bellini --json\n"
      "  tunekit nozzle --rheology peek_fit.json -T 405 --flow 3 --json       # results.prediction\n"
      "  tunekit nozzle --fit datasets/rheology/nozzle_pressure_synthetic.csv --json   # fit K, n (and Ea)");
  return sub;
}

void register_nozzle(CLI::App& app, CliContext& ctx) {
  auto cmd = std::make_shared<NozzleCommand>();
  add_nozzle_command(app, cmd->options, cmd->output)->callback([cmd, &ctx] {
    set_exit_code(report_outcome(compute_nozzle(cmd->options), cmd->output, ctx));
  });
}

}  // namespace tunekit::cli
