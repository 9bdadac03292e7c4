#pragma once
// tunekit nozzle as a function: the pressure drop of a melt through a nozzle (Hagen-Poiseuille,
// power-law capillary with the Rabinowitsch correction, Bellini's three-zone model, Boles' model)
// from rheology and geometry, with the liquefier's predicted relative time constant; or the inverse
// fit of K and n (and an activation energy) from measured flow and pressure or feeder force at known
// temperature, as in the load-cell experiments of Holtrup, Tuning liquefier dynamics, MSc thesis,
// University of Twente, 2019, sec. 5.3. The shape of a command is described in docs/cpp-api.md.

#include <cstddef>
#include <map>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/fitting/fit_result.hpp"
#include "tunekit/fitting/nozzle_pressure.hpp"
#include "tunekit/fitting/rheology_fit.hpp"
#include "tunekit/ident/liquefier_prediction.hpp"

namespace tunekit::calibration {

struct NozzleOptions {
  /// Geometry (SI; the command line reads mm and degrees), pressure-drop model and the reference
  /// flow (mm3/s) at which relative_tau is 1. Its temperature_K and flows_mm3_s are set by
  /// compute_nozzle() from `temperature_degc` and `flows_mm3_s`.
  ident::LiquefierPredictionOptions prediction;
  // The rheology, exactly one of: K and n, mu, material, rheology_json.
  double K = fitting::kNaN;                       ///< power-law consistency (Pa.s^n)
  double n = fitting::kNaN;                       ///< power-law index (1)
  double mu = fitting::kNaN;                      ///< Newtonian viscosity (Pa.s)
  std::string material;                           ///< Cross-WLF material name, or "peek-power-law"
  std::string rheology_json;                      ///< a 'tunekit rheo --json' result file
  double temperature_degc = fitting::kNaN;        ///< melt temperature (degC); NaN: not given
  double kelvin_offset = fitting::kKelvinOffset;  ///< degC to K: 273.15 or Holtrup's 273 (K)
  std::vector<double> flows_mm3_s;                ///< flows to evaluate (mm3/s); at least one without fit_file
  std::string fit_file;                           ///< non-empty: inverse fit from this CSV instead
  double piston_diameter_mm = fitting::kNaN;      ///< area a force column acts on (mm)
  std::size_t max_rows = 200000;                  ///< most rows of fit_file accepted (count; --max-rows)
};

/// One evaluated flow of the forward mode.
struct NozzlePoint {
  double flow_mm3_s = 0;
  double pressure_drop_Pa = 0;                  ///< with the chosen model
  fitting::LocalPowerLaw local;                 ///< the power law matching the rheology at the wall shear rate
  std::map<std::string, double> all_models_Pa;  ///< pressure drop by every model, by model name
};

struct NozzleForward {
  std::string rheology;                                  ///< where the viscosity came from, in words
  double temperature_K = fitting::kNaN;                  ///< NaN: no temperature given (power law, Newtonian)
  std::vector<NozzlePoint> points;                       ///< one per flow, in the order given
  std::optional<ident::LiquefierPrediction> prediction;  ///< with a temperature or a power law
};

struct NozzleFit {
  std::size_t rows = 0;    ///< measurements read
  fitting::FitResult fit;  ///< K, n (and Ea) with 95 % intervals
};

struct NozzleOutcome {
  NozzleOptions options;
  std::string input_path;  ///< the --fit CSV or the --rheology file; empty: none read
  std::string input_sha256;
  std::size_t input_size_bytes = 0;
  std::optional<NozzleForward> forward;  ///< the forward mode's results
  std::optional<NozzleFit> fit;          ///< the inverse fit's results (fit_file given)
  std::vector<std::string> warnings;
};

/// Computes the pressure drops (or the inverse fit). InputError (exit 2) for bad options or input,
/// FitError (exit 1) when the fit does not converge.
NozzleOutcome compute_nozzle(const NozzleOptions& options);

Envelope to_envelope(const NozzleOutcome& outcome);
void print_text(const NozzleOutcome& outcome, std::ostream& os);

/// A length in mm (or an angle in degrees) as the command line and the JSON show it, from the SI
/// value the library holds: rounded to 12 significant digits so that 0.6 mm reads 0.6 again.
double nozzle_display_value(double si, double per_si);

}  // namespace tunekit::calibration
