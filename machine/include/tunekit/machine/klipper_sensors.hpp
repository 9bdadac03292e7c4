#pragma once
// Klipper's sensor streams on its API server, as Klipper's own code serves them
// (O'Connor et al., Klipper 3D printer firmware, docs/API_Server.md and klippy/extras/, 2024-2025):
//
//   chip (profile)      config section          endpoint                  mux key    value
//   adxl345             [adxl345] / [adxl345 N] adxl345/dump_adxl345      "sensor"   last word of the section
//   lis2dw, lis3dh      [lis2dw N] / [lis3dh N] lis2dw/dump_lis2dw        "sensor"   (lis3dh.py builds a LIS2DW)
//   mpu9250, mpu6050    [mpu9250 N]             mpu9250/dump_mpu9250      "sensor"   (one module, chip by device id)
//   icm20948            [icm20948 N]            icm20948/dump_icm20948    "sensor"
//   bmi160              [bmi160 N]              bmi160/dump_bmi160        "sensor"
//   load cell           [load_cell] / [load_cell N]  load_cell/dump_force "load_cell" (load_cell.py's mux key;
//                                                                         the API document's example says "sensor")
//   extruder motion     -                       motion_report/dump_trapq  "name"     "extruder", "toolhead"
//
// Each subscription answers {"header": [...]} and then sends, every 0.5 s (bulk_sensor.py's
// BATCH_INTERVAL), the request's response_template with "params": {"data": [rows], "errors",
// "overflows"}. Accelerometer rows: [print_time_s, x, y, z] (mm/s^2). Load-cell rows:
// [print_time_s, force_g, counts, tare_counts] (force null while the cell is not calibrated
// and tared). Trapq rows: [print_time_s, duration_s, start_velocity, acceleration,
// [start_x, start_y, start_z], [dir_x, dir_y, dir_z]] (mm, mm/s, mm/s^2); an extruder's trapq
// carries the filament position in x, direction (1, pressure-advance flag, 0), and a signed
// velocity. All times are Klipper's print time, so samples and commanded motion share a clock.

#include <array>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace tunekit::machine {

/// A subscription request: method and the params that select the object.
struct KlipperEndpoint {
  std::string method;
  std::string key;
  std::string value;
  /// {key: value, "response_template": template}
  nlohmann::json params(const nlohmann::json& response_template) const;
};

/// The object name Klipper registers for a config section: its last word ("lis2dw toolhead" ->
/// "toolhead", "adxl345" -> "adxl345").
std::string klipper_object_name(const std::string& section);

/// The dump endpoint of an accelerometer chip (see the table above); InputError for a chip
/// Klipper does not read.
KlipperEndpoint klipper_accelerometer_endpoint(const std::string& chip, const std::string& section);
KlipperEndpoint klipper_load_cell_endpoint(const std::string& section);
KlipperEndpoint klipper_trapq_endpoint(const std::string& trapq_name);

/// Grams-force to newtons (standard gravity, 9.80665 m/s^2).
constexpr double kNewtonPerGramForce = 9.80665e-3;

struct KlipperLoadCellSample {
  double time_s = 0;
  double force_N = 0;
};

/// The "data" rows of a load_cell/dump_force message. A row without a force (the cell is not
/// calibrated or not tared) is a MachineError naming the section.
std::vector<KlipperLoadCellSample> parse_load_cell_rows(const nlohmann::json& params, const std::string& section);

struct KlipperAccelSample {
  double time_s = 0;
  double x = 0, y = 0, z = 0;  ///< mm/s^2
};
std::vector<KlipperAccelSample> parse_accel_rows(const nlohmann::json& params);

/// One trapq entry: constant acceleration along `direction` from `start_pos`.
struct TrapqMove {
  double print_time_s = 0;
  double duration_s = 0;
  double start_velocity = 0;  ///< mm/s (signed for an extruder)
  double acceleration = 0;    ///< mm/s^2
  std::array<double, 3> start_pos{};
  std::array<double, 3> direction{};
};

/// The commanded motion of one trapq (e.g. "extruder") on the print-time axis.
class TrapqTimeline {
 public:
  /// Adds the rows of a motion_report/dump_trapq message (MachineError on a malformed row).
  void add(const nlohmann::json& params);
  /// Velocity along direction[0] (for an extruder: the filament feed, mm/s) at print time t;
  /// 0 outside every move.
  double velocity_x_at(double t_s) const;
  /// Mean of that velocity over [t0_s, t1_s] (mm/s): the distance fed over the window divided by
  /// its length, what a sample standing for the window carries (a brief slow-down at a junction
  /// counts for its share of the window, not for the whole sample). t1_s <= t0_s: velocity at t0_s.
  double mean_velocity_x(double t0_s, double t1_s) const;
  const std::vector<TrapqMove>& moves() const { return moves_; }
  std::size_t size() const { return moves_.size(); }
  bool empty() const { return moves_.empty(); }

 private:
  std::vector<TrapqMove> moves_;  ///< sorted by print time
};

}  // namespace tunekit::machine
