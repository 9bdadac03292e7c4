// The simulated hot end's thermal plant and its firmware heater loop (thermal_plant.hpp).
#include "tunekit/sim/thermal_plant.hpp"

#include <algorithm>
#include <cmath>

namespace tunekit::sim {

namespace {

// Sub-steps of the block and sensor over one interval of constant inputs: the sensor's
// exponential follows the block's, which is itself exact over each sub-step.
constexpr double kPlantSubstep_s = 0.05;
// The sim's PID loop, sized from the plant as a firmware's tuning would be: crossover at half
// the sensor's rate (R / 2, a phase margin of about 60 degrees against the sensor's lag), the
// integral's corner a fifth of that.
constexpr double kCrossoverOfSensorRate = 0.5;
constexpr double kIntegralCornerOfCrossover = 0.2;

double log_uniform(std::mt19937& rng, double lo, double hi) {
  return std::exp(std::uniform_real_distribution<double>(std::log(lo), std::log(hi))(rng));
}

double uniform(std::mt19937& rng, double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }

struct PidGains {
  double kp, ki;  ///< duty per K, duty per K s
};
PidGains pid_gains(const ThermalPlantTruth& tr) {
  const auto& m = tr.model;
  const double wc = kCrossoverOfSensorRate * m.sensor_responsiveness_per_s;
  const double kp = wc * m.block_heat_capacity_j_per_k / m.heater_power_w;
  return {kp, kp * wc * kIntegralCornerOfCrossover};
}

}  // namespace

double ThermalPlantTruth::fan_loss_w_per_k(double fan_duty) const {
  const double f = std::clamp(fan_duty, 0.0, 1.0);
  return model.ambient_transfer_w_per_k +
         (model.fan_transfer_w_per_k - model.ambient_transfer_w_per_k) * std::pow(f, fan_exponent);
}

nlohmann::json ThermalPlantTruth::to_json() const {
  return {{"heater_power_w", model.heater_power_w},
          {"block_heat_capacity_j_per_k", model.block_heat_capacity_j_per_k},
          {"sensor_responsiveness_per_s", model.sensor_responsiveness_per_s},
          {"ambient_transfer_w_per_k", model.ambient_transfer_w_per_k},
          {"fan_transfer_w_per_k", model.fan_transfer_w_per_k},
          {"filament_heat_capacity_j_per_k_mm", model.filament_heat_capacity_j_per_k_mm},
          {"ambient_c", model.ambient_c},
          {"fan_exponent", fan_exponent},
          {"sensor_noise_c", sensor_noise_c},
          {"adc_step_c", adc_step_c},
          {"control_period_s", control_period_s},
          {"pwm_levels", pwm_levels}};
}

ThermalPlantTruth draw_thermal_plant(unsigned seed) {
  std::mt19937 rng(1000003u * seed + 29u);
  ThermalPlantTruth t;
  t.model.heater_power_w = log_uniform(rng, 30, 60);
  t.model.block_heat_capacity_j_per_k = log_uniform(rng, 10, 25);
  t.model.sensor_responsiveness_per_s = log_uniform(rng, 0.08, 0.35);
  t.model.ambient_transfer_w_per_k = log_uniform(rng, 0.04, 0.10);
  t.model.fan_transfer_w_per_k = t.model.ambient_transfer_w_per_k * uniform(rng, 1.3, 2.2);
  t.model.filament_heat_capacity_j_per_k_mm = log_uniform(rng, 0.004, 0.008);
  t.model.ambient_c = uniform(rng, 18, 32);
  t.fan_exponent = uniform(rng, 0.6, 1.4);
  t.sensor_noise_c = log_uniform(rng, 0.03, 0.15);
  t.adc_step_c = log_uniform(rng, 0.05, 0.25);
  return t;
}

ThermalPlant::ThermalPlant(const ThermalPlantTruth& truth) : truth_(truth) {
  block_c_ = sensor_c_ = std::isnan(truth.start_c) ? truth.model.ambient_c : truth.start_c;
}

void ThermalPlant::advance(double dt_s, double duty, double fan_duty, double fed_mm) {
  if (!(dt_s > 0)) return;
  const auto& m = truth_.model;
  const double u = std::clamp(duty, 0.0, 1.0);
  const double loss = truth_.fan_loss_w_per_k(fan_duty) + m.filament_heat_capacity_j_per_k_mm * fed_mm / dt_s;
  const double settle_c = m.ambient_c + u * m.heater_power_w / loss;  // where the block tends
  const double a = loss / m.block_heat_capacity_j_per_k, r = m.sensor_responsiveness_per_s;
  const int n = std::max(1, static_cast<int>(std::ceil(dt_s / kPlantSubstep_s)));
  const double h = dt_s / n;
  for (int k = 0; k < n; ++k) {
    // Block: exponential towards settle_c. Sensor: dTs/dt = r (Tb - Ts), exactly, with
    // (e^{-a h} - e^{-r h}) / (r - a) = e^{-a h} h expm1((a - r) h) / ((a - r) h).
    const double d0 = block_c_ - settle_c, x = (a - r) * h;
    const double phi = std::abs(x) < 1e-12 ? 1.0 : std::expm1(x) / x;
    const double ea = std::exp(-a * h), er = std::exp(-r * h);
    sensor_c_ = settle_c + d0 * r * ea * h * phi + (sensor_c_ - settle_c) * er;
    block_c_ = settle_c + d0 * ea;
  }
}

SimHeater::SimHeater(const ThermalPlantTruth& truth, unsigned noise_seed) : plant_(truth), rng_(noise_seed) {
  reading_c_ = read_sensor();
  tick();
}

void SimHeater::set_target(double target_c) {
  if (target_c <= 0) off();  // off at once, not at the next tick
  else target_c_ = target_c;
}

void SimHeater::set_fan(double fan_duty) { fan_ = std::clamp(fan_duty, 0.0, 1.0); }

void SimHeater::off() {
  target_c_ = 0;
  duty_ = 0;
  integral_ = 0;
}

void SimHeater::settle(double target_c) {
  set_target(target_c);
  if (target_c_ <= 0) return;
  plant_.set_temperature(target_c_);
  const auto& tr = plant_.truth();
  const auto& m = tr.model;
  const double hold = tr.fan_loss_w_per_k(fan_) * (target_c_ - m.ambient_c) / m.heater_power_w;
  integral_ = std::clamp(hold, 0.0, 1.0) / pid_gains(tr).ki;
}

double SimHeater::read_sensor() {
  const auto& tr = plant_.truth();
  const double noisy = plant_.sensor_c() + tr.sensor_noise_c * normal_(rng_);
  return tr.adc_step_c > 0 ? tr.adc_step_c * std::round(noisy / tr.adc_step_c) : noisy;
}

// One heater-loop tick: the reading, the PID's duty (the integral held while the duty is at a
// limit, as firmware's anti-windup does), quantised to the PWM's levels, and the record's sample.
void SimHeater::tick() {
  const auto& tr = plant_.truth();
  reading_c_ = read_sensor();
  const double period = tr.control_period_s;
  if (!record_.t_s.empty()) {
    record_.feed_mm_s.back() = fed_since_tick_ / period;
    record_.fan_duty.back() = fan_time_since_tick_ / period;
  }
  fed_since_tick_ = fan_time_since_tick_ = 0;
  if (target_c_ <= 0) {
    duty_ = 0;
    integral_ = 0;
  } else {
    const auto [kp, ki] = pid_gains(tr);
    const double error = target_c_ - reading_c_;
    const double raw = kp * error + ki * (integral_ + error * period);
    if (raw > 0 && raw < 1) integral_ += error * period;
    const double levels = tr.pwm_levels > 0 ? tr.pwm_levels : 1e9;
    duty_ = std::round(std::clamp(raw, 0.0, 1.0) * levels) / levels;
  }
  record_.t_s.push_back(t_);
  record_.temp_c.push_back(reading_c_);
  record_.heater_duty.push_back(duty_);
  record_.fan_duty.push_back(fan_);
  record_.feed_mm_s.push_back(0);  // both filled at the next tick: the means over the interval
  record_.target_c.push_back(target_c_);
  to_tick_ = period;
}

void SimHeater::advance(double dt_s, double fed_mm) {
  double left = dt_s;
  while (left > 0) {
    const double h = std::min(left, to_tick_);
    const double fed = dt_s > 0 ? fed_mm * h / dt_s : 0;
    plant_.advance(h, duty_, fan_, fed);
    fed_since_tick_ += fed;
    fan_time_since_tick_ += fan_ * h;
    t_ += h;
    to_tick_ -= h;
    left -= h;
    if (to_tick_ <= 1e-12) tick();
  }
}

ident::ThermalRecord run_thermal_schedule(const ThermalPlantTruth& truth, const std::vector<ThermalSetting>& schedule,
                                          double end_s, unsigned noise_seed) {
  SimHeater heater(truth, noise_seed);
  double t = 0;
  for (std::size_t i = 0; i < schedule.size(); ++i) {
    const auto& s = schedule[i];
    heater.set_target(s.target_c);
    heater.set_fan(s.fan_duty);
    const double until = std::min(end_s, i + 1 < schedule.size() ? schedule[i + 1].from_s : end_s);
    if (until > t) heater.advance(until - t, s.feed_mm_s * (until - t));
    t = std::max(t, until);
  }
  heater.off();
  ident::ThermalRecord r = heater.record();
  // The last sample is the tick at the end: its interval lies beyond the record.
  return r;
}

}  // namespace tunekit::sim
