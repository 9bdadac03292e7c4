#pragma once
// Shared by the protocol builders (experiments.cpp dispatches to experiments_liquefier.cpp,
// experiments_axis.cpp and experiments_print.cpp): the G-code helpers of experiment_gcode.cpp
// and the builders themselves. Not installed; the public API is tunekit/protocols/experiments.hpp.

#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tunekit/protocols/experiments.hpp"

namespace tunekit::protocols::experiment_gcode {

/// How the firmware runs an extrude-only feed: Klipper brings every extrude-only move to a full
/// stop (klippy/toolhead.py Move.calc_junction returns early unless both moves are kinematic),
/// Marlin and RepRapFirmware blend consecutive extrude-only moves in the same direction.
/// `accel_mm_s2` is the acceleration the firmware applies to them; `max_len_mm` the longest
/// extrude-only move it accepts.
struct FeedPlan {
  bool stops = false;
  double accel_mm_s2 = 0;
  double max_len_mm = 50;
};

/// The middle of the axis' travel (mm).
double mid(const machine::MachineProfile& p, const std::string& axis);
/// `v` with at most `decimals` decimals, trailing zeros dropped ("-0" is "0").
std::string num(double v, int decimals = 4);
/// Klipper: the acceleration a test restores (SET_VELOCITY_LIMIT ACCEL): the one in force when
/// the machine was identified, else the profile's print acceleration; mm/s^2.
inline double accel_to_restore(const machine::MachineProfile& p) {
  return p.state.accel_in_force_mm_s2 > 0 ? p.state.accel_in_force_mm_s2 : p.print.max_accel_mm_s2;
}
void feed_move(std::vector<std::string>& g, const FeedPlan& fp, double feed_mm_s, double duration_s);
FeedPlan extruder_accel(std::vector<std::string>& g, std::vector<std::string>& restore, double a,
                        const machine::MachineProfile& profile, const firmware::Dialect& d);
/// Relative extrusion, the hot end heated (if asked) and the extrude-only acceleration set.
FeedPlan liquefier_prologue(std::vector<std::string>& g, std::vector<std::string>& restore,
                            const std::map<std::string, double>& p, const machine::MachineProfile& profile,
                            const firmware::Dialect& d);
void epilogue(std::vector<std::string>& g, const std::vector<std::string>& restore);
void shaping_off(const machine::MachineProfile& profile, const firmware::Dialect& d, std::vector<std::string>& prologue,
                 std::vector<std::string>& restore, nlohmann::json& changed);
void record_feed_plan(Experiment& e, const FeedPlan& fp);
void check_plan(const std::string& protocol, double lines, double duration_s, const ProtocolLimits& limits);
void guard_line_count(const std::vector<std::string>& g, const ProtocolLimits& limits, const std::string& protocol);

/// What build_experiment was asked for.
struct ExperimentRequest {
  Protocol id;
  const std::string& protocol;  ///< its name
  const std::map<std::string, double>& overrides;
  const std::string& axis_in;
  const machine::MachineProfile& profile;
  const firmware::Dialect& dialect;
  const ProtocolLimits& limits;
};

/// Each family's builder appends its protocol's G-code and excitation to `e` (parameters filled
/// in and checked); false when the protocol is not of its family.
bool build_liquefier_experiment(const ExperimentRequest& r, Experiment& e);
bool build_axis_experiment(const ExperimentRequest& r, Experiment& e);
bool build_print_experiment(const ExperimentRequest& r, Experiment& e);
/// heater-identify (thermal_plan.cpp).
void build_thermal_experiment(const ExperimentRequest& r, Experiment& e);

}  // namespace tunekit::protocols::experiment_gcode
