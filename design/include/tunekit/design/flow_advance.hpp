#pragma once
// Flow-dependent pressure advance designed from a liquefier whose time constant depends on the
// flow (shear thinning: tau falls as the flow rises; Holtrup, Tuning liquefier dynamics, MSc
// thesis, University of Twente, 2019, Table 4.3), and its fit to every form of flow-dependent
// advance that firmware and slicers accept (docs/export.md).
//
// Derivation. Model the liquefier as one store of melt volume V (mm^3) fed by the extruder
// (flow Q_in) and emptied through the nozzle (flow Q_out) whose outflow depends on the stored
// volume alone: dV/dt = Q_in - Q_out, Q_out = g(V), g increasing. Linearized about a steady
// flow Q, a small change of Q_in reaches Q_out first order with the time constant
// tau(Q) = dV/dQ_out (the incremental compliance of the store), which is what a step test at
// that level identifies. So the volume stored at steady flow Q, counted from the empty
// (pressure-free) state, is
//     V(Q) = integral_0^Q tau(q) dq                                               (mm^3)
// and an extruder that pushes exactly V(Q) ahead of the nominal filament (filament offset
// V(Q) / A_f mm, A_f the filament cross-section) delivers Q_out = Q_in at every instant: the lag
// is cancelled for any speed history, not only for small steps. Firmware pushes the filament
// offset as a function of the nominal filament speed v = Q / A_f:
//   - Klipper, Marlin, RepRapFirmware: offset = K * v, one K (s). Exact only where V(Q) = K Q;
//     the K the liquefier needs at flow Q is K(Q) = V(Q) / Q (the mean of tau over 0..Q, NOT
//     tau(Q): with tau falling with flow, K(Q) > tau(Q)). With a constant tau, K = tau.
//   - Kalico's nonlinear models: offset = linear_advance * v + nonlinear_offset * f(v / v_lin)
//     (f = tanh or 1 - 1/(1+x)), fitted to V(Q)/A_f over the identified flows.
//   - OrcaSlicer's adaptive pressure advance: a table of (K, flow, acceleration) that the slicer
//     interpolates per feature: K(Q) at the identified flows.
// Assumptions (stated in the export's notes): (1) one store, first order at every level (the
// dead time theta is a pure delay and is not part of V); (2) the steady gain is 1 (flow out =
// flow in at steady state; a gain other than 1 is an extrusion-multiplier matter); (3) below the
// lowest identified level tau is held at that level's value (a Newtonian melt at low shear);
// between levels tau is interpolated linearly, or follows the fitted power law tau = a Q^b when
// one is given (then V = a Q^(b+1) / (b+1), needing b > -1; below the lowest level the estimate
// follows the power law and its lower bound holds tau there); above the highest level tau is held; (4) the acceleration
// does not enter: a linear store's need does not depend on it.
//
// 95 % band. When each level carries an interval for tau, the band of the need is computed with
// every level at its lower (upper) bound: V is monotone in every tau, so this brackets V(Q) for
// any combination of taus inside their intervals (conservative: the levels' errors are taken as
// fully correlated).

#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tunekit/design/pressure_advance.hpp"

namespace tunekit::design {

/// tau identified at one flow level (with its 95 % interval when known).
struct FlowTau {
  double flow_mm3_s = kAdvanceNaN;
  double tau_s = kAdvanceNaN;
  double tau_lo_s = kAdvanceNaN;  ///< 95 % interval, NaN when unknown
  double tau_hi_s = kAdvanceNaN;
};

/// tau(Q) = a * Q^b with Q in mm^3/s (power-law trend of the levels).
struct TauPowerLaw {
  double a = kAdvanceNaN;
  double b = kAdvanceNaN;
};

/// Kalico's nonlinear advance models (Kalico, bleeding-edge-v2, klippy/chelper/kin_extruder.c
/// pressure_advance_tanh_model_func / pressure_advance_recipr_model_func;
/// klippy/kinematics/extruder.py PATanhModel.name "tanh", PAReciprModel.name "recipr").
enum class KalicoModel { tanh, recipr };
std::string to_string(KalicoModel m);

/// Kalico's filament offset (mm) at filament speed v (mm/s), exactly as kin_extruder.c computes
/// it: linear_advance * v + nonlinear_offset * f(v / linearization_velocity), f(x) = tanh(x) or
/// 1 - 1/(1+x); the nonlinear term only when nonlinear_offset is non-zero.
double kalico_offset_mm(KalicoModel m, double linear_advance_s, double nonlinear_offset_mm,
                        double linearization_velocity_mm_s, double v_mm_s);

struct KalicoFit {
  KalicoModel model = KalicoModel::tanh;
  double linear_advance_s = kAdvanceNaN;             ///< `linear_advance`, s (mm per mm/s)
  double nonlinear_offset_mm = kAdvanceNaN;          ///< `nonlinear_offset`, mm of filament
  double linearization_velocity_mm_s = kAdvanceNaN;  ///< `linearization_velocity`, mm/s of filament
  double max_rel_error = kAdvanceNaN;                ///< max |fit - need| / need over the fitted flows
  double rms_rel_error = kAdvanceNaN;
};

/// One OrcaSlicer adaptive pressure advance measurement line: "advance,flow,acceleration".
struct OrcaPoint {
  double k_s = kAdvanceNaN;
  double flow_mm3_s = kAdvanceNaN;
  double accel_mm_s2 = kAdvanceNaN;
};

/// The stored volume at one flow, measured rather than integrated from tau (a record's start-up
/// transient from rest, rest_volume.hpp), with its 95 % half-width.
struct MeasuredVolume {
  double flow_mm3_s = kAdvanceNaN;
  double volume_mm3 = kAdvanceNaN;
  double half_width_mm3 = kAdvanceNaN;
};

struct FlowAdvanceInputs {
  std::vector<FlowTau> levels;       ///< >= 2 levels with distinct positive flows
  std::optional<TauPowerLaw> trend;  ///< used for tau(Q) instead of interpolation when given
  /// With a trend: the volume below the data is this measurement instead of a bound, V(Q) =
  /// volume + integral of the trend from its flow to Q; the band is the measurement's half-width
  /// and the trend's (trend_rel_half_width of its integral), added in quadrature (the two come
  /// from different parts of the record).
  std::optional<MeasuredVolume> low_volume;
  /// With a trend: the sensor read the stored volume at every level (a pressure sensor), so the
  /// trend's V(Q) from zero flow is measured, not extrapolated; its band is V's relative half-width.
  bool volume_measured = false;
  double volume_rel_half_width = kAdvanceNaN;
  double trend_rel_half_width = kAdvanceNaN;  ///< the trend's tau, widest relative 95 % half-width
  /// The trend's covariance, when its fit gave one: tau = tau_ref (Q / reference_flow)^b with
  /// {var(ln tau_ref), cov(ln tau_ref, b), var(b)}. With it the band of a known volume is the
  /// delta method's 95 % interval of V(Q) (else the widest relative half-width above, conservative).
  struct TrendCovariance {
    double reference_flow_mm3_s = kAdvanceNaN;
    double var_ln_tau_ref = kAdvanceNaN, cov_ln_tau_ref_b = kAdvanceNaN, var_b = kAdvanceNaN;
  };
  std::optional<TrendCovariance> trend_covariance;
  double filament_area_mm2 = kAdvanceNaN;
  double design_flow_mm3_s = kAdvanceNaN;  ///< flow the single-number K is designed for
  double theta_s = kAdvanceNaN;            ///< identified dead time (Kalico's time offset)
  /// Accelerations (mm/s^2) the OrcaSlicer table is written for (the need does not depend on
  /// it; OrcaSlicer interpolates between accelerations and uses a single set for every
  /// acceleration). Empty: one set, at 0 mm/s^2.
  std::vector<double> orca_accels_mm_s2;
  double tolerance = 0.10;  ///< band of the single K: flows where |K - K(Q)| <= tolerance K(Q)
  int samples = 64;         ///< points of the curves over the identified range
};

struct FlowAdvanceSample {
  double flow_mm3_s = kAdvanceNaN;
  double tau_s = kAdvanceNaN;
  double k_need_s = kAdvanceNaN;  ///< V(Q)/Q
  double k_lo_s = kAdvanceNaN;    ///< band (NaN without intervals)
  double k_hi_s = kAdvanceNaN;
  double offset_need_mm = kAdvanceNaN;  ///< V(Q)/A_f
  double k_kalico_s = kAdvanceNaN;      ///< the chosen Kalico fit, as an equivalent K
};

struct FlowAdvanceDesign {
  double flow_min_mm3_s = kAdvanceNaN;  ///< identified range
  double flow_max_mm3_s = kAdvanceNaN;
  double design_flow_mm3_s = kAdvanceNaN;
  double k_design_s = kAdvanceNaN;  ///< single K = V(Qd)/Qd (Klipper, Marlin, RepRapFirmware)
  /// Bounds of the single K (s): the levels' 95 % intervals when they carry them, and, with a
  /// power-law trend, the volume below the lowest identified flow taken at both of its bounds.
  double k_design_lo_s = kAdvanceNaN;
  double k_design_hi_s = kAdvanceNaN;
  /// Share of V(Qd) that lies below the lowest identified flow (NaN without a power-law trend).
  double low_flow_share = kAdvanceNaN;
  /// Flows (within the identified range) where the single K is within the tolerance of the need.
  double k_within_lo_mm3_s = kAdvanceNaN;
  double k_within_hi_mm3_s = kAdvanceNaN;
  KalicoFit kalico;                           ///< the better of the two models
  KalicoFit kalico_other;                     ///< the other model, for the record
  double kalico_time_offset_s = kAdvanceNaN;  ///< `pressure_advance_time_offset` = theta (clamped)
  std::vector<OrcaPoint> orca;                ///< sorted by flow, then acceleration
  std::vector<FlowAdvanceSample> curve;
  bool has_band = false;
  bool band_from_levels = false;  ///< the band holds the levels' 95 % intervals (else only the low flows')
  /// The band is the 95 % interval of the need (a measured low volume or a volume-reading sensor
  /// with the trend's own widths): k_design_lo_s..k_design_hi_s needs no further widening.
  bool band_is_interval = false;
  std::vector<std::string> notes;
  std::vector<std::string> warnings;

  nlohmann::json to_json() const;
};

/// tau at flow q (s) under the assumptions above; `which` -1 lower bound, 0 estimate, +1 upper.
double flow_tau_s(const FlowAdvanceInputs& in, double q_mm3_s, int which = 0);
/// Stored volume V(Q) = integral_0^Q tau(q) dq (mm^3).
double stored_volume_mm3(const FlowAdvanceInputs& in, double q_mm3_s, int which = 0);
/// The single advance the liquefier needs at flow Q: V(Q)/Q (s).
double needed_advance_s(const FlowAdvanceInputs& in, double q_mm3_s, int which = 0);

/// Least-squares fit (relative errors) of one Kalico model to the needed offset at `flows`.
KalicoFit fit_kalico(const FlowAdvanceInputs& in, KalicoModel model, const std::vector<double>& flows);

/// Designs every form. Throws InputError for fewer than two usable levels, non-positive flows
/// or taus, or a missing filament area. A power law with a <= 0 or b <= -1 (no finite stored
/// volume from zero flow) is set aside with a warning and the levels' table designed from.
FlowAdvanceDesign design_flow_advance(const FlowAdvanceInputs& in);

}  // namespace tunekit::design
