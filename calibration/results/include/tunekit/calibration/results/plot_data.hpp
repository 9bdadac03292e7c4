#pragma once
// The series behind the report's plots, typed: what RUN_DIR/plotdata.json holds (one member per
// plot, report.hpp lists them) and what the report's figures are drawn from. NaN in a series is
// a gap (no value at that sample; JSON null in plotdata.json). Units are in the member names.

#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace tunekit::calibration {

/// A step record: time (s), the commanded input, the measured output, each step's fit over its
/// step (NaN elsewhere) and the whole-record model's output (empty when it was not fitted).
struct StepPlot {
  std::string u_label, y_label;  ///< axis labels with units ("feed (mm/s)")
  std::vector<double> t_s, u, y, y_fit, y_model;
  std::string model_label;    ///< the whole-record model's legend text, when y_model is given
  std::string model_missing;  ///< why there is no whole-record model; empty when there is one
  bool has_model() const { return !y_model.empty(); }
};

/// A curve of a Bode plot: frequency (Hz), magnitude (dB), phase (deg).
struct BodeSeries {
  std::vector<double> freq_hz, mag_db, phase_deg;
};

/// The measured frequency response with its coherence (empty: none) and the reported fitted model.
struct BodePlot {
  BodeSeries measured;
  std::vector<double> coherence;
  struct Model {
    BodeSeries curve;
    std::string label;
  };
  std::optional<Model> model;
};

/// One axis' PSD ((mm/s^2)^2/Hz against Hz), its modes and each candidate shaper's remaining
/// vibration (fraction) at the identified damping; `recommended` the shaper chosen.
struct PsdPlot {
  std::vector<double> freq_hz, psd;
  std::vector<double> mode_freq_hz;
  struct Shaper {
    std::string type;
    std::vector<double> freq_hz, response;
  };
  std::vector<Shaper> shapers;
  struct Recommended {
    std::string type;
    double freq_hz = 0;
  };
  std::optional<Recommended> recommended;
};

/// The advance the liquefier needs against flow (design::FlowAdvanceDesign's curve, s against
/// mm^3/s), with its band, the exported models and, from `tunekit export`, the rheology prediction.
struct FlowAdvancePlot {
  std::vector<double> flow_mm3_s, tau_s, k_need_s, k_lo_s, k_hi_s, k_kalico_s;
  std::string kalico_model;  ///< Kalico's pressure_advance_model; empty when not known
  double k_single_s = std::numeric_limits<double>::quiet_NaN();         ///< the single K (s)
  double design_flow_mm3_s = std::numeric_limits<double>::quiet_NaN();  ///< the flow it is designed for
  std::vector<double> orca_flow_mm3_s, orca_k_s;                        ///< OrcaSlicer's table
  struct Rheology {
    std::vector<double> flow_mm3_s, tau_pred_s;
    double max_gap_rel = std::numeric_limits<double>::quiet_NaN();
  };
  std::optional<Rheology> rheology;
};

/// The line test's first line: width and set-point (mm) along the arc length (mm), and the photo
/// overlay (a PNG, relative to the run directory; empty: none).
struct LinewidthPlot {
  std::vector<double> s_mm, width_mm, setpoint_mm;
  std::string overlay_png;
};

/// The overshoot grid (`tunekit overshoot -p ...`): one cell per speed x acceleration.
struct OvershootGridPlot {
  double tolerance_mm = 0;
  struct Cell {
    bool input_shaping = false;
    double speed_mm_s = 0, accel_mm_s2 = 0, overshoot_mm = 0, completion_time_s = 0, figure_of_merit = 0;
  };
  std::vector<Cell> cells;
};

/// Viscosity (Pa s) against shear rate (1/s), measured and fitted, per temperature (K).
struct ViscosityPlot {
  struct Series {
    double temperature_K = 0;
    std::vector<double> shear_rate_1_s, viscosity_Pa_s, fit_shear_rate_1_s, fit_viscosity_Pa_s;
  };
  std::vector<Series> series;
};

/// Every plot of a report; an absent member is a plot left out.
struct ReportPlots {
  std::optional<StepPlot> step;
  std::optional<BodePlot> bode;
  std::map<std::string, PsdPlot> psd;  ///< by axis ("x", "y", "z")
  std::optional<OvershootGridPlot> overshoot_grid;
  std::optional<FlowAdvancePlot> flow_advance;
  std::optional<ViscosityPlot> viscosity;
  std::optional<LinewidthPlot> linewidth;
  /// The hot end's thermal record (calibrate --thermal): heater duty as the input, the measured
  /// temperature and the fitted model's (y_model, over the held-out part too); y_fit unused.
  std::optional<StepPlot> thermal;
};

}  // namespace tunekit::calibration
