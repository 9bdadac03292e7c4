#include "tunekit/firmware/thermal_export.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <numbers>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/firmware/config_edit.hpp"
#include "tunekit/firmware/firmware_export.hpp"

namespace tunekit::firmware {
namespace {

// Klipper's PID_CALIBRATE saves the gains with "%.3f" (klippy/extras/pid_calibrate.py).
constexpr int kDecimalsPid = 3;
// Kalico's MPC_CALIBRATE saves with "#.6g"; these decimals keep 6 significant digits at the
// values a hot end has (P tens of W, C about 10-30 J/K, R and A below 1).
constexpr int kDecimalsKalicoPower = 3;
constexpr int kDecimalsKalicoCapacity = 4;
constexpr int kDecimalsKalicoSmall = 6;
// Marlin's M306 report (Marlin/src/gcode/temp/M306.cpp): P, C with 2 decimals; R, A, F, H with 4.
constexpr int kDecimalsMarlinPC = 2;
constexpr int kDecimalsMarlinSmall = 4;
// RepRapFirmware's M307 (src/Heating/FOPDT.cpp AppendM307Command): R, K with 3, D, E, S with 2.
constexpr int kDecimalsRrfRate = 3;
constexpr int kDecimalsRrfTime = 2;

double written(double v, int decimals) { return std::strtod(format_number(v, decimals).c_str(), nullptr); }

ThermalOption num(const std::string& option, double v, int decimals) {
  return {option, format_number(v, decimals), true, v, decimals};
}

/// Kalico's fan_ambient_transfer: the model's loss A + f (F - A) at n evenly spaced fan speeds.
std::string kalico_fan_list(const ThermalExport& t) {
  const auto& m = t.model;
  std::string out;
  const int n = std::max(2, t.kalico_fan_breakpoints);
  for (int i = 0; i < n; ++i) {
    const double f = static_cast<double>(i) / (n - 1);
    const double loss = m.ambient_transfer_w_per_k + f * (m.fan_transfer_w_per_k - m.ambient_transfer_w_per_k);
    out += (i ? ", " : "") + format_number(loss, kDecimalsKalicoSmall);
  }
  return out;
}

/// Kalico's filament_heat_capacity, J/(g K): H (J/(K mm)) over the grams in a millimetre of
/// filament, density (g/cm^3 = 1e-3 g/mm^3) times its cross-section.
double kalico_specific_heat(const ThermalExport& t) {
  const double area_mm2 = std::numbers::pi * t.filament_diameter_mm * t.filament_diameter_mm / 4.0;
  return t.model.filament_heat_capacity_j_per_k_mm / (t.filament_density_g_cm3 * 1e-3 * area_mm2);
}

bool is_kalico_mpc(ExportFirmware fw, const ThermalExport& t) { return fw == ExportFirmware::kalico && !t.kalico_pid; }

}  // namespace

std::vector<ThermalOption> thermal_klipper_options(ExportFirmware fw, const ThermalExport& t) {
  std::vector<ThermalOption> out;
  if (!is_kalico_mpc(fw, t)) {
    const auto gains = design::klipper_pid_gains(design::design_thermal_pid(t.model, t.pid));
    out.push_back({"control", "pid", false, 0, 0});
    out.push_back(num("pid_kp", gains.kp, kDecimalsPid));
    out.push_back(num("pid_ki", gains.ki, kDecimalsPid));
    out.push_back(num("pid_kd", gains.kd, kDecimalsPid));
    return out;
  }
  const auto& m = t.model;
  out.push_back({"control", "mpc", false, 0, 0});
  out.push_back(num("heater_power", m.heater_power_w, kDecimalsKalicoPower));
  out.push_back(num("block_heat_capacity", m.block_heat_capacity_j_per_k, kDecimalsKalicoCapacity));
  out.push_back(num("sensor_responsiveness", m.sensor_responsiveness_per_s, kDecimalsKalicoSmall));
  out.push_back(num("ambient_transfer", m.ambient_transfer_w_per_k, kDecimalsKalicoSmall));
  out.push_back({"fan_ambient_transfer", kalico_fan_list(t), false, 0, 0});
  if (m.filament_heat_capacity_j_per_k_mm > 0)
    out.push_back(num("filament_heat_capacity", kalico_specific_heat(t), kDecimalsKalicoCapacity));
  return out;
}

std::string thermal_klipper_gcode(ExportFirmware fw, const ThermalExport& t, const std::string& section) {
  if (!is_kalico_mpc(fw, t)) return {};
  // Kalico's MPC_SET (klippy/extras/control_mpc.py cmd_MPC_SET): the model's constants at run time
  // (the heater's power is read from the configuration only).
  const auto& m = t.model;
  std::string fan = kalico_fan_list(t);
  fan.erase(std::remove(fan.begin(), fan.end(), ' '), fan.end());
  std::string g = fmt::format(
      "MPC_SET HEATER={} BLOCK_HEAT_CAPACITY={} SENSOR_RESPONSIVENESS={} AMBIENT_TRANSFER={} "
      "FAN_AMBIENT_TRANSFER={}",
      section, format_number(m.block_heat_capacity_j_per_k, kDecimalsKalicoCapacity),
      format_number(m.sensor_responsiveness_per_s, kDecimalsKalicoSmall),
      format_number(m.ambient_transfer_w_per_k, kDecimalsKalicoSmall), fan);
  if (m.filament_heat_capacity_j_per_k_mm > 0)
    g += " FILAMENT_HEAT_CAPACITY=" + format_number(kalico_specific_heat(t), kDecimalsKalicoCapacity);
  return g + "\n";
}

std::vector<MarlinThermalDefine> marlin_mpc_defines(const ThermalExport& t) {
  const auto& m = t.model;
  std::vector<MarlinThermalDefine> d = {
      {"MPC_HEATER_POWER", m.heater_power_w, kDecimalsMarlinPC},
      {"MPC_BLOCK_HEAT_CAPACITY", m.block_heat_capacity_j_per_k, kDecimalsMarlinPC},
      {"MPC_SENSOR_RESPONSIVENESS", m.sensor_responsiveness_per_s, kDecimalsMarlinSmall},
      {"MPC_AMBIENT_XFER_COEFF", m.ambient_transfer_w_per_k, kDecimalsMarlinSmall},
      {"MPC_AMBIENT_XFER_COEFF_FAN255", m.fan_transfer_w_per_k, kDecimalsMarlinSmall},
  };
  if (m.filament_heat_capacity_j_per_k_mm > 0)
    d.push_back({"FILAMENT_HEAT_CAPACITY_PERMM", m.filament_heat_capacity_j_per_k_mm, kDecimalsMarlinSmall});
  return d;
}

std::string marlin_m306_gcode(const ThermalExport& t, int extruder) {
  // M306.cpp: E selects the hotend, P C R A set the model, F the loss at full fan (applyFanAdjustment
  // stores F - A), H the filament's heat capacity per mm.
  std::string g = fmt::format("M306 E{}", extruder);
  static const char kLetters[] = {'P', 'C', 'R', 'A', 'F', 'H'};
  const auto defs = marlin_mpc_defines(t);
  for (std::size_t i = 0; i < defs.size(); ++i)
    g += fmt::format(" {}{}", kLetters[i], format_number(defs[i].value, defs[i].decimals));
  return g + "\n";
}

RrfM307Values rrf_m307_values(const ThermalExport& t) {
  const auto r = design::rrf_heater_model(t.model, t.rrf_cooling_exponent, t.rrf_match_rise_k, t.pid.loop_delay_s);
  return {format_number(r.heating_rate_k_s, kDecimalsRrfRate),
          format_number(r.cooling_rate_k_s, kDecimalsRrfRate) + ":" +
              format_number(r.fan_cooling_rate_k_s, kDecimalsRrfRate),
          format_number(r.dead_time_s, kDecimalsRrfTime), format_number(r.cooling_exponent, kDecimalsRrfTime)};
}

namespace {

void validate_rrf(const ThermalExport& t, std::vector<std::string>& bad) {
  // src/Heating/FOPDT.cpp FopDt::SetParameters, on the values as written.
  const auto r = design::rrf_heater_model(t.model, t.rrf_cooling_exponent, t.rrf_match_rise_k, t.pid.loop_delay_s);
  const double hr = written(r.heating_rate_k_s, kDecimalsRrfRate), cr = written(r.cooling_rate_k_s, kDecimalsRrfRate);
  const double fr = written(r.fan_cooling_rate_k_s, kDecimalsRrfRate), dt = written(r.dead_time_s, kDecimalsRrfTime);
  const std::string src = "(src/Heating/FOPDT.cpp SetParameters)";
  if (!(cr > 0) || hr / cr < 0.1)
    bad.push_back(
        fmt::format("RepRapFirmware refuses M307 R{} K{}: \"estimated temperature rise too small\" (R/K "
                    "below 0.1) {}",
                    hr, cr, src));
  if (fr < 0)
    bad.push_back(
        fmt::format("RepRapFirmware refuses a negative fan cooling rate K..:{} (\"fan reduces cooling "
                    "rate\": the model's F is below A) {}",
                    fr, src));
  if (dt <= 0.0099)
    bad.push_back(fmt::format("RepRapFirmware refuses the dead time D{} (\"dead time too small\") {}", dt, src));
  if (dt * cr > 50.0)
    bad.push_back(
        fmt::format("RepRapFirmware refuses D{} with K{} (\"dead time too close to cooling time constant\", "
                    "D K above 50) {}",
                    dt, cr, src));
  if (!(t.rrf_max_pwm > 0.0099 && t.rrf_max_pwm <= 1.0))
    bad.push_back(fmt::format("RepRapFirmware's M307 S (max PWM) must be above 0.0099 and at most 1, not {} {}",
                              t.rrf_max_pwm, src));
  if (t.rrf_heater < 0) bad.push_back(fmt::format("the heater number must be >= 0, not {}", t.rrf_heater));
}

void validate_kalico_mpc(const ThermalExport& t, std::vector<std::string>& bad) {
  if (!(t.filament_density_g_cm3 > 0) || !(t.filament_diameter_mm > 0))
    bad.push_back(
        fmt::format("Kalico's filament_density and filament_diameter must be above 0 (heaters.py above=0.), "
                    "not {} g/cm^3 and {} mm",
                    t.filament_density_g_cm3, t.filament_diameter_mm));
  if (t.kalico_fan_breakpoints < 2)
    bad.push_back(
        fmt::format("Kalico's fan_ambient_transfer needs at least 2 breakpoints, not {}", t.kalico_fan_breakpoints));
  const auto& m = t.model;
  if (!(written(m.fan_transfer_w_per_k, kDecimalsKalicoSmall) >= 0))
    bad.push_back(fmt::format("the fan's ambient transfer must be >= 0 W/K, not {}", m.fan_transfer_w_per_k));
  if (m.filament_heat_capacity_j_per_k_mm < 0)
    bad.push_back(
        fmt::format("Kalico's filament_heat_capacity must be above 0 (heaters.py above=0.), not from H = {} "
                    "J/(K mm)",
                    m.filament_heat_capacity_j_per_k_mm));
}

}  // namespace

void validate_thermal(ExportFirmware fw, const ThermalExport& t, std::vector<std::string>& bad) {
  const auto& m = t.model;
  // Every firmware's model needs these above 0 (Kalico heaters.py: heater_power, block_heat_capacity,
  // sensor_responsiveness above=0.; Marlin's and RRF's models divide by them).
  // The upper ends are a hot end's, with a wide margin: cartridges of 30-80 W, blocks of 5-50 J/K
  // (Marlin's MPC documentation gives 40 W and 16.7 J/K as typical); a value past them is a typing
  // error or a failed fit, and would be written into the firmware as it stands.
  const struct {
    const char* what;
    double v;
    int decimals;
    double max;
  } required[] = {{"heater power P (W)", m.heater_power_w, kDecimalsMarlinPC, 1000.0},
                  {"block heat capacity C (J/K)", m.block_heat_capacity_j_per_k, kDecimalsMarlinPC, 1000.0},
                  {"sensor responsiveness R (1/s)", m.sensor_responsiveness_per_s, kDecimalsMarlinSmall, 100.0},
                  {"ambient transfer A (W/K)", m.ambient_transfer_w_per_k, kDecimalsMarlinSmall, 100.0}};
  for (const auto& q : required) {
    if (!(written(q.v, q.decimals) > 0))
      bad.push_back(fmt::format("the thermal model's {} must be above 0 as written, not {}", q.what, q.v));
    else if (!(q.v <= q.max))
      bad.push_back(fmt::format("the thermal model's {} is {:g}, more than any hot end's {:g}", q.what, q.v, q.max));
  }
  if (!(m.fan_transfer_w_per_k <= 100.0) || !(m.filament_heat_capacity_j_per_k_mm <= 1.0))
    bad.push_back(
        "the thermal model's fan transfer F (at most 100 W/K) or filament heat capacity H (at most 1 "
        "J/(K mm)) is beyond any hot end's");
  if (!std::isfinite(m.fan_transfer_w_per_k) || !std::isfinite(m.filament_heat_capacity_j_per_k_mm))
    bad.push_back("the thermal model's fan transfer F and filament heat capacity H must be numbers");
  if (!bad.empty()) return;  // the designs below need a valid model
  if (fw == ExportFirmware::rrf) validate_rrf(t, bad);
  if (is_kalico_mpc(fw, t)) validate_kalico_mpc(t, bad);
  if (fw == ExportFirmware::marlin && m.fan_transfer_w_per_k < m.ambient_transfer_w_per_k)
    bad.push_back(
        fmt::format("Marlin's MPC_AMBIENT_XFER_COEFF_FAN255 ({} W/K) is below MPC_AMBIENT_XFER_COEFF ({} W/K): "
                    "the fan would warm the hot end",
                    m.fan_transfer_w_per_k, m.ambient_transfer_w_per_k));
  if (fw == ExportFirmware::klipper || (fw == ExportFirmware::kalico && t.kalico_pid)) {
    try {
      (void)design::design_thermal_pid(m, t.pid);
    } catch (const InputError& e) {
      bad.push_back(e.message());
    }
  }
}

}  // namespace tunekit::firmware
