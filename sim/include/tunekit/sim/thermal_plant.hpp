#pragma once
// The simulated printer's hot end as a thermal plant with known truth, beside its liquefier:
// a heater block and a sensor with its own lag (ident/thermal_model.hpp states the equations),
// a loss to the ambient that grows with the part-cooling fan's duty f as A + (F - A) f^gamma
// (gamma = 1: the linear loss of Marlin's model; the simulated fan's may be bent either way),
// the heat the filament takes with the feed, the heater's power limit (its duty is held in
// [0, 1], quantised as the firmware's PWM is), and the thermistor read through an ADC: noise,
// then the converter's step.
//
// The firmware's heater loop (SimHeater) runs a PID controller on the sensor's reading at a fixed
// period, as Marlin's and Klipper's heater loops do, and applies its duty until the next tick;
// each tick is one sample of the record (time, reading, duty, fan, mean feed, target). A stop
// (SimHeater::off) sets the target to 0 and the duty to 0 at once.
//
// Units: temperatures degC, time s, power W, feed mm/s of filament.

#include <limits>
#include <random>
#include <vector>

#include <nlohmann/json.hpp>

#include "tunekit/ident/thermal_model.hpp"
#include "tunekit/ident/thermal_record.hpp"

namespace tunekit::sim {

/// The truth of one simulated hot end.
struct ThermalPlantTruth {
  /// The model's parameters: P, C, R, A, F (the loss at full fan), H and the ambient.
  ident::ThermalModel model{40.0, 18.0, 0.2, 0.065, 0.10, 0.0056, 25.0};
  double fan_exponent = 1.0;      ///< gamma of the fan loss A + (F - A) f^gamma
  double sensor_noise_c = 0.08;   ///< the thermistor reading's noise (standard deviation), degC
  double adc_step_c = 0.1;        ///< the reading's quantisation step near printing temperature, degC
  double control_period_s = 1.0;  ///< the heater loop's period (one record sample per tick), s
  double pwm_levels = 127;        ///< the duty's resolution: Marlin's soft PWM (0..127)
  double start_c = kNaN;          ///< the block's and sensor's temperature at power-up; NaN: the ambient
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  /// The loss to the ambient at fan duty f in [0, 1], W/K.
  double fan_loss_w_per_k(double fan_duty) const;
  nlohmann::json to_json() const;
};

/// A hot end drawn from `seed` for coverage runs, log-uniform (uniform for the ambient and the
/// exponent) within the ranges of desktop hot ends: P 30-60 W, C 10-25 J/K, R 0.08-0.35 1/s,
/// A 0.04-0.10 W/K, F 1.3-2.2 times A, H 0.004-0.008 J/K/mm (1.75 mm filament), ambient
/// 18-32 degC, fan exponent 0.6-1.4, noise 0.03-0.15 degC, ADC step 0.05-0.25 degC.
ThermalPlantTruth draw_thermal_plant(unsigned seed);

/// The block and the sensor: the physics alone, advanced over an interval of constant inputs.
class ThermalPlant {
 public:
  explicit ThermalPlant(const ThermalPlantTruth& truth);
  /// Advances `dt_s` with the heater at `duty` (clamped to [0, 1]), the fan at `fan_duty` and
  /// `fed_mm` of filament fed evenly over the interval, integrated exactly over sub-steps.
  void advance(double dt_s, double duty, double fan_duty, double fed_mm);
  /// Block and sensor at `temp_c`, at rest (a wait that has passed).
  void set_temperature(double temp_c) { block_c_ = sensor_c_ = temp_c; }
  double block_c() const { return block_c_; }
  double sensor_c() const { return sensor_c_; }
  const ThermalPlantTruth& truth() const { return truth_; }

 private:
  ThermalPlantTruth truth_;
  double block_c_, sensor_c_;
};

/// The firmware's heater loop around a ThermalPlant: a PID controller on the reading at the
/// truth's control period. Time advances by `advance`; every whole period is one tick that reads
/// the sensor, sets the duty and appends a sample to the record.
class SimHeater {
 public:
  SimHeater(const ThermalPlantTruth& truth, unsigned noise_seed);
  /// The target temperature (degC); 0 turns the heater off at once (off()).
  void set_target(double target_c);
  void set_fan(double fan_duty);
  /// A stop: target 0, duty 0, from this instant.
  void off();
  /// The target set and reached at once (block and sensor at it, the controller's integral at
  /// the duty that holds it with the fan at its duty): a firmware's wait that has passed.
  void settle(double target_c);
  /// Advances `dt_s` with `fed_mm` of filament fed evenly over it.
  void advance(double dt_s, double fed_mm);
  double target_c() const { return target_c_; }
  double fan_duty() const { return fan_; }
  double duty() const { return duty_; }
  /// The last reading (what M105 reports), degC.
  double reading_c() const { return reading_c_; }
  /// The loop's time, s since the simulator started.
  double time_s() const { return t_; }
  const ThermalPlant& plant() const { return plant_; }
  /// Every tick so far: t_s, temp_c (the reading), heater_duty (applied from that tick on),
  /// fan_duty and feed_mm_s (the means over the interval that starts at the tick, filled at the
  /// next tick), target_c (the target the tick's duty was computed for).
  const ident::ThermalRecord& record() const { return record_; }

 private:
  void tick();
  double read_sensor();
  ThermalPlant plant_;
  std::mt19937 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  double t_ = 0, to_tick_ = 0;
  double target_c_ = 0, fan_ = 0, duty_ = 0, reading_c_ = 0;
  double integral_ = 0, last_error_ = 0;
  double fed_since_tick_ = 0, fan_time_since_tick_ = 0;
  ident::ThermalRecord record_;
};

/// One piece of a thermal schedule: from `from_s` on, the target, the fan's duty and the feed.
struct ThermalSetting {
  double from_s = 0;
  double target_c = 0;
  double fan_duty = 0;
  double feed_mm_s = 0;
};

/// The simulated hot end run through `schedule` (pieces in time order, the first from 0) up to
/// `end_s`: the record its heater loop samples, as the firmware's reports give it. Settings
/// change at the pieces' start; the heater is off at the end.
ident::ThermalRecord run_thermal_schedule(const ThermalPlantTruth& truth, const std::vector<ThermalSetting>& schedule,
                                          double end_s, unsigned noise_seed);

}  // namespace tunekit::sim
