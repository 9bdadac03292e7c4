#pragma once
// tunekit resonance --load-kg: the bed axis of a bed slinger swept with known masses on the bed
// (tunekit run axis-sweep -p load_kg=...), one accelerometer record per mass. Each record's
// first mode is identified as `tunekit resonance` does; f(m) = sqrt(k / (m0 + m)) / (2 pi) is
// fitted to them (ident/bed_mass.hpp: m0 and k with 95 % intervals and their correlation, the
// damping's trend); records given as held out are predicted, not fitted, and their error
// stated. With the print's mass (or a sliced file) the schedule follows: Marlin's M493 D2 lines,
// Prusa's M593 weight adjustment and M74, and Klipper's per-layer SET_INPUT_SHAPER in the sliced
// G-code (firmware/bed_mass_export.hpp).

#include <ostream>
#include <string>
#include <vector>

#include "tunekit/calibration/analyses/resonance_common.hpp"
#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/firmware/bed_mass_export.hpp"
#include "tunekit/ident/bed_mass.hpp"

namespace tunekit::calibration {

struct BedMassOptions {
  AccelFilesOptions accel;            ///< the fitted records (accel.files) and how each is read
  std::vector<double> loads_kg;       ///< the mass on the bed in each fitted record, in file order
  std::vector<std::string> held_out;  ///< records predicted, not fitted
  std::vector<double> held_out_loads_kg;
  std::vector<double> predict_g;        ///< further masses (g) to predict the frequency at
  double print_mass_g = fitting::kNaN;  ///< the print's mass (g): Marlin's and Prusa's lines; NaN: none
  double filament_diameter_mm = 1.75;
  double filament_density_g_cm3 = 1.24;           ///< PLA
  std::string shaper = "mzv";                     ///< the shaper type Marlin's and Prusa's lines set
  double shaper_zeta = 0.1;                       ///< its damping ratio
  std::string marlin_m493_form = "axis_list_v2";  ///< firmware::parse_m493_syntax's names
  std::string gcode_in, gcode_out;                ///< a sliced file and where its schedule goes
  std::string gcode_firmware = "klipper";         ///< klipper, kalico (SET_INPUT_SHAPER) or prusa (M74 W)
  double step_hz = 0.5;                           ///< the per-layer schedule's smallest change
  std::string plot;  ///< the figure (SVG or PNG): f(m), its band, the sweeps, the print's layers
};

struct BedMassRecord {
  ident::BedMassPoint point;
  std::string method;  ///< how its mode was fitted (ident::AxisModes::method)
};

struct BedMassOutcome {
  BedMassOptions options;
  std::vector<BedMassRecord> records;  ///< the fitted ones
  ident::BedMassFit fit;
  std::vector<ident::BedHeldOutCheck> held_out;
  std::vector<ident::BedFrequencyPrediction> predictions;
  std::optional<design::LinearMassSchedule> schedule;  ///< over the print's mass
  double grams_per_mm = 0;
  std::vector<std::string> marlin_lines, prusa_lines;
  std::optional<firmware::GcodeMassResult> gcode;
  std::vector<InputDigest> inputs;
  std::vector<std::string> warnings;
};

/// Reads and fits every record, fits f(m), predicts the held-out records and the masses asked
/// for, and writes the schedule. InputError (exit 2) for bad options (a mass per record, at
/// least two masses), FitError (exit 1) when a record shows no mode or the fit fails.
BedMassOutcome compute_bed_mass(const BedMassOptions& options);
Envelope to_envelope(const BedMassOutcome& outcome);
void print_text(const BedMassOutcome& outcome, std::ostream& os);

}  // namespace tunekit::calibration
