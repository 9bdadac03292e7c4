// tunekit rheo: the command line of the command (options bound straight into the library's
// option structs, so --help shows the library's defaults); the work is done by the
// calibration library's compute function.

#include "tunekit/cli/command.hpp"
#include "tunekit/cli/analysis_commands.hpp"
#include "tunekit/cli/commands.hpp"
#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/cli/option_binding.hpp"
#include "tunekit/calibration/analyses/rheo_command.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/fitting/rheology_fit.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/ident/liquefier_prediction.hpp"
#include "tunekit/formats/rheology_data.hpp"
#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <memory>
#include <numbers>
#include <tuple>

namespace tunekit::cli {

using namespace calibration;

namespace {
struct RheoCommand {
  RheoOptions options;
  OutputOptions output;
};

// Reading the file: its columns, their units and temperatures, the rows fitted.
void add_csv_options(CLI::App* sub, RheoOptions& o) {
  sub->add_option("--shear-rate", o.csv.shear_rate_column, "Shear-rate column (1/s) when not named shear_rate");
  sub->add_option("--viscosity", o.csv.viscosity_column, "Viscosity column when not named viscosity or eta");
  sub->add_option("--shear-stress", o.csv.stress_column, "Shear-stress column (viscosity = stress / shear rate)");
  sub->add_option("--temperature-col", o.csv.temperature_column, "Temperature column when not named temperature");
  sub->add_option("--pressure-col", o.csv.pressure_column, "Pressure column when not named pressure");
  sub->add_option("--stress-unit", o.csv.stress_unit, "Unit of the shear-stress column: Pa, kPa, MPa");
  sub->add_option("--temperature-unit", o.csv.temperature_unit, "Unit of the temperature column: degC or K");
  sub->add_option("--t-ref", o.t_ref_degc,
                  "Reference temperature of the shift (degC; default: the middle data temperature)");
  sub->add_option("--temperature", o.csv.temperature_degC,
                  "Temperature of every point when the file has no temperature column (degC)");
  sub->add_option("--kelvin-offset", o.csv.kelvin_offset,
                  "degC to K offset: 273.15 (SI) or 273 (as Holtrup's (2019) code) (K)")
      ->capture_default_str();
  sub->add_option("--viscosity-unit", o.csv.viscosity_unit,
                  "Unit of the viscosity column when its header states none: Pa.s, mPa.s, cP, P (poise) or kPa.s");
  sub->add_option("--temperatures", o.temperatures,
                  "Fit only the rows at LO:HI degC (inclusive; either side may be empty), e.g. 300:350");
}

// A power law fitted to the model over a window of shear rates.
void add_power_law_options(CLI::App* sub, RheoOptions& o) {
  sub->add_option(
      "--power-law-window", o.power_law_window,
      "Fit K (Pa.s^n) and n of a power law to the fitted model over LOW:HIGH shear rates (1/s), e.g. 600:950");
  sub->add_option("--power-law-points", o.power_law_points, "Log-spaced points in the power-law window (count)")
      ->capture_default_str();
  sub->add_option("--power-law-at", o.power_law_at_degc,
                  "Temperatures of the power-law fits (degC; default: the data's)");
}

// The liquefier prediction: the nozzle's geometry, the temperature and flows, the pressure model.
void add_prediction_options(CLI::App* sub, RheoOptions& o) {
  auto& geometry = o.prediction.geometry;
  // The geometry is kept in m and rad (fitting::NozzleGeometry, with its defaults); the command
  // line speaks mm and degrees.
  const auto mm = [](double m) { return fmt::format("{:g}", m * 1e3); };
  sub->add_option_function<double>(
         "--nozzle-d",
         [&opts = o, &geometry](double d_mm) {
           opts.predict = true;
           geometry.d_m = d_mm * 1e-3;
         },
         "Nozzle channel diameter d (mm); enables the liquefier prediction")
      ->type_name("FLOAT");
  sub->add_option_function<double>(
         "--nozzle-l", [&geometry](double v) { geometry.l_m = v * 1e-3; }, "Nozzle land length l (mm)")
      ->type_name("FLOAT")
      ->default_str(mm(geometry.l_m));
  sub->add_option_function<double>(
         "--cone-angle", [&geometry](double v) { geometry.cone_half_angle_rad = v * std::numbers::pi / 180.0; },
         "Nozzle cone half angle alpha (degrees)")
      ->type_name("FLOAT")
      ->default_str(
          fmt::format("{:g}", std::round(geometry.cone_half_angle_rad * 180.0 / std::numbers::pi * 1e9) / 1e9));
  sub->add_option_function<double>(
         "--entrance-D", [&geometry](double v) { geometry.D_m = v * 1e-3; }, "Melt room / entrance diameter D (mm)")
      ->type_name("FLOAT")
      ->default_str(mm(geometry.D_m));
  sub->add_option("--predict-at", o.predict_at_degc,
                  "Melt temperature of the prediction (degC; default: the middle data temperature)");
  sub->add_option("--flows", o.prediction.flows_mm3_s, "Operating flows of the prediction (mm3/s)");
  sub->add_option("--reference-flow", o.prediction.reference_flow_mm3_s, "Flow at which relative_tau is 1 (mm3/s)")
      ->capture_default_str();
  add_parsed_option(
      sub, "--pressure-model", o.prediction.model, fitting::parse_pressure_model,
      [](fitting::PressureModel m) { return fitting::to_string(m); }, "boles, bellini, power-law or hagen-poiseuille");
}

}  // namespace

CLI::App* add_rheo_command(CLI::App& app, RheoOptions& o, OutputOptions& output) {
  auto* sub = app.add_subcommand("rheo", "Fit melt viscosity models (power law, Cross, Cross-WLF, Carreau-Yasuda)");
  sub->add_option("file", o.file,
                  "CSV with shear_rate (1/s), viscosity (Pa.s|mPa.s) or shear_stress (Pa), temperature (degC|K), "
                  "optional pressure (Pa) and weight")
      ->required();
  sub->add_option("-m,--model", o.model, "newtonian, power-law, cross, cross-wlf, carreau-yasuda, or auto (lowest AIC)")
      ->capture_default_str();
  sub->add_option("--shift", o.shift,
                  "Temperature shift for models other than cross-wlf: none, arrhenius, wlf, or auto "
                  "(arrhenius when the data hold several temperatures)")
      ->capture_default_str();
  add_csv_options(sub, o);
  sub->add_option("--fix", o.fix,
                  "Hold a parameter at a value, NAME=VALUE in the parameter's SI unit (e.g. D2_K=416); repeatable. "
                  "cross-wlf holds A2_K=51.6 K and D3_K_per_Pa=0 by default");
  sub->add_option("--free", o.free,
                  "Estimate a parameter held by default (A2_K, D3_K_per_Pa, eta_inf_Pa_s); repeatable");
  sub->add_flag_callback(
      "--no-compare", [&opts = o] { opts.compare = false; }, "Fit only the chosen model (no AIC comparison)");
  sub->add_flag("--tts", o.tts, "Time-temperature superposition: shift factors a_T (1) and the master curve");
  add_power_law_options(sub, o);
  add_prediction_options(sub, o);
  sub->add_option("--max-rows", o.max_rows, "Most data rows accepted (count); a longer file is refused")
      ->capture_default_str()
      ->check(CLI::Range(std::size_t{1}, std::size_t{100000000}));
  add_output_options(sub, output);
  sub->footer(
      "Examples:\n"
      "  tunekit rheo datasets/rheology/peek_cross_wlf_synthetic.csv --model cross-wlf --json\n"
      "  tunekit rheo melt.csv --model cross --shift arrhenius --tts\n"
      "  tunekit rheo datasets/rheology/peek_cross_wlf_synthetic.csv --model cross-wlf --power-law-window 600:950 \\\n"
      "      --power-law-at 390 --power-law-at 405 --power-law-at 450\n"
      "  tunekit rheo datasets/rheology/peek_cross_wlf_synthetic.csv --model cross-wlf --nozzle-d 0.6 --nozzle-l 4 \\\n"
      "      --cone-angle 30 --entrance-D 5 --predict-at 405 --reference-flow 3 --json   # results.prediction\n"
      "  tunekit rheo abs.csv --model cross-wlf --fix D2_K=378.15 --require 'n<0.5'\n"
      "  tunekit rheo datasets/rheology/polyimidazole_melt_viscosity.csv --temperatures 300:350\n"
      "  tunekit rheo melt.csv --viscosity-unit mPa.s     # a viscosity column without a unit\n"
      "Intervals: linearised (Wald) where they hold, profile likelihood where a parameter is strongly\n"
      "correlated, near a bound or on a curved likelihood (params.X.ci95_method). With data at several\n"
      "temperatures results.superposition tests each temperature against the master curve and names\n"
      "the temperatures that do not superpose (a transition, a degraded sample).\n"
      "Parameters (SI): n, tau_star_Pa, D1_Pa_s, D2_K, D3_K_per_Pa, A1, A2_K (cross-wlf); eta0_Pa_s, K_Pa_s_n,\n"
      "lambda_s, a, eta_inf_Pa_s; shifts Ea_J_per_mol or C1, C2_K with T_ref_K.");
  return sub;
}

void register_rheo(CLI::App& app, CliContext& ctx) {
  auto cmd = std::make_shared<RheoCommand>();
  add_rheo_command(app, cmd->options, cmd->output)->callback([cmd, &ctx] {
    set_exit_code(report_outcome(compute_rheo(cmd->options), cmd->output, ctx));
  });
}

}  // namespace tunekit::cli
