// tunekit resonance --load-kg: the options of the bed-slinger analysis (the bed axis swept with
// known masses on the bed); the work is done by calibration::compute_bed_mass.

#include "bed_mass_cli.hpp"

namespace tunekit::cli {

void add_bed_mass_options(CLI::App* sub, calibration::BedMassOptions& o) {
  sub->add_option("--load-kg", o.loads_kg,
                  "Bed slinger: the mass (kg) on the bed in each record, one per file in order (0 for the empty "
                  "bed); fits the bed axis' f(m) = sqrt(k / (m0 + m)) / (2 pi)");
  sub->add_option("--held-out", o.held_out, "A record at another mass, predicted by the fit and not fitted");
  sub->add_option("--held-out-load-kg", o.held_out_loads_kg, "The mass (kg) on the bed in each --held-out record");
  sub->add_option("--predict-g", o.predict_g, "A print mass (g) to predict the frequency at (repeatable)");
  sub->add_option("--print-mass-g", o.print_mass_g,
                  "The print's mass (g): Marlin's M493 D2 and Prusa's M593 weight adjustment over it (default: the "
                  "sliced file's, with --gcode-in)");
  sub->add_option("--filament-diameter", o.filament_diameter_mm, "Filament diameter (mm)")->capture_default_str();
  sub->add_option("--filament-density", o.filament_density_g_cm3, "Filament density (g/cm^3; PLA 1.24)")
      ->capture_default_str();
  sub->add_option("--schedule-shaper", o.shaper, "The shaper type Marlin's and Prusa's lines set")
      ->capture_default_str();
  sub->add_option("--schedule-zeta", o.shaper_zeta, "Its damping ratio")->capture_default_str();
  sub->add_option("--m493-form", o.marlin_m493_form,
                  "Marlin's M493 letters: axis_slash, axis_named, axis_list (F/H scaling) or axis_list_v2 "
                  "(FTM V2: M493 Y F)")
      ->capture_default_str();
  sub->add_option("--gcode-in", o.gcode_in, "A sliced G-code file to schedule the Y frequency in, layer by layer");
  sub->add_option("--gcode-out", o.gcode_out, "Where the scheduled G-code goes");
  sub->add_option("--gcode-firmware", o.gcode_firmware,
                  "klipper or kalico (SET_INPUT_SHAPER SHAPER_FREQ_Y=) or prusa (M74 W<g>)")
      ->capture_default_str();
  sub->add_option("--step-hz", o.step_hz, "Write a new frequency only when it moved by more than this (Hz)")
      ->capture_default_str();
  sub->add_option("--plot", o.plot,
                  "Write the figure of f(m), its band, the sweeps and the print's layers (SVG or PNG)");
}

}  // namespace tunekit::cli
