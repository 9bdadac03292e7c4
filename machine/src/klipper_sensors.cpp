#include "tunekit/machine/klipper_sensors.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/machine/machine_profile.hpp"

namespace tunekit::machine {
namespace {

struct KlipperChip {
  const char* chip;    // what a profile names
  const char* module;  // the klippy/extras module whose endpoint serves it
};

// lis3dh.py constructs lis2dw.LIS2DW; an MPU-6050 is read by mpu9250.py (chip found by device id).
constexpr KlipperChip kKlipperChips[] = {{"adxl345", "adxl345"},   {"lis2dw", "lis2dw"},   {"lis3dh", "lis2dw"},
                                         {"mpu9250", "mpu9250"},   {"mpu6050", "mpu9250"}, {"mpu6500", "mpu9250"},
                                         {"icm20948", "icm20948"}, {"bmi160", "bmi160"}};

double finite_number(const nlohmann::json& v, const char* what) {
  if (!v.is_number()) throw MachineError(fmt::format("Klipper sent a {} that is not a number: {}", what, v.dump()));
  const double d = v.get<double>();
  if (!std::isfinite(d)) throw MachineError(fmt::format("Klipper sent a non-finite {}", what));
  return d;
}

const nlohmann::json& data_rows(const nlohmann::json& params) {
  static const nlohmann::json empty = nlohmann::json::array();
  if (!params.is_object() || !params.contains("data")) return empty;
  const auto& d = params["data"];
  if (!d.is_array()) throw MachineError("Klipper sent a sensor message whose \"data\" is not a list");
  return d;
}

}  // namespace

bool is_klipper_accelerometer_chip(const std::string& chip) {
  return std::any_of(std::begin(kKlipperChips), std::end(kKlipperChips), [&](const auto& c) { return chip == c.chip; });
}

std::string klipper_accelerometer_chips() {
  std::string s;
  for (const auto& c : kKlipperChips) s += (s.empty() ? "" : ", ") + std::string(c.chip);
  return s;
}

nlohmann::json KlipperEndpoint::params(const nlohmann::json& response_template) const {
  return {{key, value}, {"response_template", response_template}};
}

std::string klipper_object_name(const std::string& section) {
  std::string s = section;
  while (!s.empty() && s.back() == ' ') s.pop_back();
  const auto sp = s.find_last_of(" \t");
  return sp == std::string::npos ? s : s.substr(sp + 1);
}

KlipperEndpoint klipper_accelerometer_endpoint(const std::string& chip, const std::string& section) {
  for (const auto& c : kKlipperChips)
    if (chip == c.chip)
      return {fmt::format("{}/dump_{}", c.module, c.module), "sensor",
              klipper_object_name(section.empty() ? chip : section)};
  throw InputError(fmt::format("'{}' is not an accelerometer Klipper reads ({})", chip, klipper_accelerometer_chips()));
}

KlipperEndpoint klipper_load_cell_endpoint(const std::string& section) {
  return {"load_cell/dump_force", "load_cell", klipper_object_name(section.empty() ? "load_cell" : section)};
}

KlipperEndpoint klipper_trapq_endpoint(const std::string& trapq_name) {
  return {"motion_report/dump_trapq", "name", trapq_name};
}

std::vector<KlipperLoadCellSample> parse_load_cell_rows(const nlohmann::json& params, const std::string& section) {
  std::vector<KlipperLoadCellSample> out;
  for (const auto& row : data_rows(params)) {
    if (!row.is_array() || row.size() < 2)
      throw MachineError("Klipper sent a load-cell row that is not [time, force, ...]");
    if (row[1].is_null())
      throw MachineError(
          fmt::format("the load cell [{}] sends no force: it is not calibrated or not tared "
                      "(run LOAD_CELL_CALIBRATE and LOAD_CELL_TARE in Klipper)",
                      section));
    out.push_back({finite_number(row[0], "load-cell time"), finite_number(row[1], "force") * kNewtonPerGramForce});
  }
  return out;
}

std::vector<KlipperAccelSample> parse_accel_rows(const nlohmann::json& params) {
  std::vector<KlipperAccelSample> out;
  for (const auto& row : data_rows(params)) {
    if (!row.is_array() || row.size() < 4)
      throw MachineError("Klipper sent an accelerometer row that is not [time, x, y, z]");
    out.push_back({finite_number(row[0], "sample time"), finite_number(row[1], "x acceleration"),
                   finite_number(row[2], "y acceleration"), finite_number(row[3], "z acceleration")});
  }
  return out;
}

void TrapqTimeline::add(const nlohmann::json& params) {
  for (const auto& row : data_rows(params)) {
    if (!row.is_array() || row.size() < 6 || !row[4].is_array() || row[4].size() < 3 || !row[5].is_array() ||
        row[5].size() < 3)
      throw MachineError(
          "Klipper sent a trapq row that is not [time, duration, start_velocity, acceleration, "
          "start_position, direction]");
    TrapqMove m;
    m.print_time_s = finite_number(row[0], "trapq time");
    m.duration_s = finite_number(row[1], "trapq duration");
    m.start_velocity = finite_number(row[2], "trapq start velocity");
    m.acceleration = finite_number(row[3], "trapq acceleration");
    for (std::size_t k = 0; k < 3; ++k) {
      m.start_pos[k] = finite_number(row[4][k], "trapq position");
      m.direction[k] = finite_number(row[5][k], "trapq direction");
    }
    moves_.push_back(m);
  }
  // Batches arrive in time order, each in time order; keep the list sorted anyway.
  std::stable_sort(moves_.begin(), moves_.end(),
                   [](const auto& a, const auto& b) { return a.print_time_s < b.print_time_s; });
}

double TrapqTimeline::velocity_x_at(double t) const {
  auto it = std::upper_bound(moves_.begin(), moves_.end(), t,
                             [](double v, const TrapqMove& m) { return v < m.print_time_s; });
  if (it == moves_.begin()) return 0;
  const TrapqMove& m = *std::prev(it);
  const double dt = t - m.print_time_s;
  if (dt > m.duration_s + 1e-9) return 0;
  return (m.start_velocity + m.acceleration * std::min(dt, m.duration_s)) * m.direction[0];
}

double TrapqTimeline::mean_velocity_x(double t0, double t1) const {
  if (!(t1 > t0)) return velocity_x_at(t0);
  // The first move that ends after t0; moves are sorted by start and do not overlap.
  auto it = std::upper_bound(moves_.begin(), moves_.end(), t0,
                             [](double v, const TrapqMove& m) { return v < m.print_time_s; });
  if (it != moves_.begin()) --it;
  double distance = 0;
  for (; it != moves_.end() && it->print_time_s < t1; ++it) {
    const double a = std::max(t0, it->print_time_s) - it->print_time_s;
    const double b = std::min(t1, it->print_time_s + it->duration_s) - it->print_time_s;
    if (!(b > a)) continue;
    // Integral of v0 + acc s over s in [a, b].
    distance += (it->start_velocity * (b - a) + 0.5 * it->acceleration * (b * b - a * a)) * it->direction[0];
  }
  return distance / (t1 - t0);
}

}  // namespace tunekit::machine
