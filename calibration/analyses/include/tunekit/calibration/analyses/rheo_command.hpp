#pragma once
// tunekit rheo as a function: melt viscosity models (Newtonian, power law, Cross, Cross-WLF,
// Carreau-Yasuda, with Arrhenius or WLF temperature shifts) fitted to rheometer data and compared
// by AIC; power laws over a shear-rate window; the time-temperature superposition check; and the
// liquefier's flow-dependent resistance predicted for a nozzle geometry (Holtrup, Tuning liquefier
// dynamics, MSc thesis, University of Twente, 2019, ch. 5). Shape of a command: command.hpp.

#include <cstddef>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/fitting/rheology_fit.hpp"
#include "tunekit/ident/liquefier_prediction.hpp"
#include "tunekit/formats/rheology_data.hpp"

namespace tunekit::calibration {

struct RheoOptions {
  std::string file;
  /// Columns, units, the temperature of a file without one, the degC -> K offset; the
  /// temperature range is filled in from `temperatures` by compute_rheo().
  formats::RheologyCsvOptions csv;
  std::string temperatures;           ///< "LO:HI" degC, either side may be empty; empty: every row
  std::string model = "auto";         ///< a viscosity model name, or auto (lowest AIC)
  std::string shift = "auto";         ///< none, arrhenius, wlf, or auto (arrhenius with several temperatures)
  double t_ref_degc = fitting::kNaN;  ///< shift reference (degC); NaN: the middle data temperature
  std::vector<std::string> fix;       ///< NAME=VALUE (SI), parameters held at a value
  std::vector<std::string> free;      ///< parameters held by default to estimate instead
  bool compare = true;                ///< fit the default candidates too and rank them by AIC
  bool tts = false;                   ///< report the master curve's shift factors
  std::string power_law_window;       ///< "LOW:HIGH" 1/s; empty: no power-law fits
  int power_law_points = 50;          ///< log-spaced points in the window (Holtrup 2019, sec. 5.2.3)
  /// Most data rows accepted (count): a rheometer file holds tens to hundreds; the bound keeps a
  /// runaway file from running for minutes (--max-rows).
  std::size_t max_rows = 20000;
  std::vector<double> power_law_at_degc;  ///< temperatures of the power-law fits; empty: the data's
  /// The liquefier prediction (geometry in m and rad, flows in mm3/s); made when `predict`.
  bool predict = false;
  ident::LiquefierPredictionOptions prediction;
  double predict_at_degc = fitting::kNaN;  ///< melt temperature (degC); NaN: the middle data temperature
};

struct RheoPowerLaw {
  double temperature_K = 0;
  fitting::FitResult fit;  ///< K_Pa_s_n and n
};

struct RheoOutcome {
  RheoOptions options;
  std::string input_sha256;
  std::size_t input_size_bytes = 0;
  std::size_t num_points = 0;
  std::vector<double> temperatures_K;  ///< the data's temperature levels
  fitting::FitResult fit;              ///< the chosen (or best) model
  std::optional<fitting::ModelComparison> comparison;
  std::vector<RheoPowerLaw> power_laws;
  std::pair<double, double> power_law_window_1_s{0, 0};
  std::optional<fitting::SuperpositionCheck> superposition;  ///< data at several temperatures
  std::optional<ident::LiquefierPrediction> prediction;
  std::vector<std::string> warnings;
};

/// InputError (exit 2) for bad data or options; FitError (exit 1) when no model can be fitted.
RheoOutcome compute_rheo(const RheoOptions& options);

Envelope to_envelope(const RheoOutcome& outcome);
void print_text(const RheoOutcome& outcome, std::ostream& os);

}  // namespace tunekit::calibration
