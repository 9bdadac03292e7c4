#pragma once
// tunekit's virtual printer: a G-code machine following Marlin's, Klipper's or RepRapFirmware's
// planner rules (SimConfig::firmware) with a simulated liquefier and
// load cell, axes with resonant modes and an accelerometer, and injectable faults. It runs
// in-process on any Transport (a socket pair in tests) or on a pseudo-terminal (SimPtyServer,
// and the tunekit-sim executable). Its truth (the parameters it simulates) is written to
// truth.json so identification can be held against it.
//
// Simulated time: the machine clock advances only by executed motion and dwells, computed as
// fast as the host reads; it is not tied to wall time. Sample timestamps are machine time (s).
//
// Protocol (docs/machine.md): lines "N<n> <cmd>*<cs>" or plain "<cmd>"; answers "ok", or
// "Error:checksum mismatch, Last Line: <n>" + "Resend: <n+1>" + "ok". Moves are queued with a
// one-move lookahead (consecutive same-direction moves blend at the first move's speed) and run
// when the next move, G4, M400, M4100, G28 or M410 arrives. Sensor streaming (M4100):
//   M4100 A1 / A0   accelerometer on/off: "echo:TKA <t_s> <ax> <ay> <az> <cmd_ax> <cmd_ay>" (mm/s^2),
//                   and each piece of commanded motion the simulator runs meanwhile, "echo:TKM <t0_s>
//                   <duration_s> <accel_x> <accel_y> <jerk_x> <jerk_y>" (mm/s^2, mm/s^3): the
//                   acceleration accel + jerk * (t - t0) over [t0, t0 + duration]
//   M4100 L1 / L0   load cell on/off:     "echo:TKL <t_s> <feed_mm_s> <force_N>"
//   M4100 H1 / H0   hot end on/off: each tick of the heater loop (thermal_plant.hpp), one period
//                   late, "echo:TKH <t_s> <temp_c> <target_c> <heater_duty> <fan_duty> <feed_mm_s>"
//                   (the duty applied from t_s on, the fan's and the feed's means until the next tick)
// The hot end is a thermal plant (thermal_plant.hpp): M104 sets its target, M106/M107 its fan,
// M105 reports its reading and duty (Marlin's "@:" in 0..127); M109 returns at once with the hot
// end settled at its target; M112 turns the heater off. M155 S<s> (Marlin's temperature
// auto-report, AUTO_REPORT_TEMPERATURES): every s seconds of machine time (at most 60; S0 stops),
// the first s seconds after M155, " T:<reading> /<target> B:<bed> /<bed target> @:<0..127> B@:0"
// from the heater loop's last tick; with SimConfig::autoreport_temp off, "Unknown command".
// M115 answers "FIRMWARE_NAME:Marlin 2.1.2 (tunekit-sim ...)" and "Cap:TUNEKIT_SENSOR_STREAM:1".

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <random>
#include <set>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "tunekit/ident/base_excited_mode.hpp"
#include "tunekit/machine/gcode.hpp"
#include "tunekit/machine/machine_profile.hpp"
#include "tunekit/machine/trajectory.hpp"
#include "tunekit/machine/transport.hpp"
#include "tunekit/sim/thermal_plant.hpp"

namespace tunekit::sim {

struct SimMode {
  double freq_hz = 0;
  double zeta = 0;
  double weight = 1;  ///< share of the axis' response (weights of an axis should sum to 1)
};

struct SimFault {
  enum class Kind { drop, garble, late_ok, disconnect, error };
  Kind kind = Kind::drop;
  long at_line = 0;     ///< 1-based count of lines the simulator received
  double delay_ms = 0;  ///< late_ok only
  std::string describe() const;
};

/// The simulated liquefier's model (option "liquefier=fopdt|physics", parsed once).
enum class LiquefierModel { fopdt, physics };

/// A named set of the simulated printer's truth (option "preset=NAME", applied before the other
/// options, whatever their order):
///   desktop  (the default) a desktop printer with a direct-drive extruder printing PLA: a liquefier
///            time constant of tens of milliseconds that falls as the flow rises, a short dead time,
///            and axis modes of 48 Hz (X) and 42 Hz (Y) with damping ratios of 0.08 and 0.09;
///   peek     the high-viscosity PEEK liquefier of Holtrup's thesis ("Tuning liquefier dynamics: A
///            strategy for accuracy improvement in extrusion based additive manufacturing with
///            PEEK", 2019): Bellini's literature
///            model (tau 0.45 s, theta 0.04 s; Bellini, Guceri and Bertoldi, "Liquefier dynamics in
///            fused deposition", 2004) with a time constant that does not change with the flow, on
///            axes with modes of 48 Hz and 37 Hz (tunekit's simulated printer before the desktop
///            default).
enum class SimPreset { desktop, peek };

struct SimConfig {
  SimPreset preset = SimPreset::desktop;
  LiquefierModel liquefier = LiquefierModel::fopdt;
  // First order plus dead time, feed (mm/s) -> force (N), with a time constant that depends on the
  // flow leaving the nozzle (the model's output as a filament feed u = force / K):
  // tau(u) = tau_s (u / tau_ref_feed_mm_s)^b, b = tau_flow_exponent, u not below
  // sim::kTauFloorFeed_mm_s. Around a steady feed u0 the small-signal time constant is tau(u0).
  // A shear-thinning melt behind a compliant filament column has b = n - 1 (n the power-law index;
  // SimConfig's physics model below): the time constant falls as the flow rises.
  //
  // Desktop defaults. A direct-drive extruder needs a pressure advance of a few hundredths of a
  // second: Klipper's "Pressure advance" guide (O'Connor, Klipper documentation) prints its tuning
  // tower for direct drives at FACTOR .005 s/mm, a quarter of the Bowden setups' .020; Wilkins and
  // Lock ("Duet3D Research - Extrusion Behaviour and Pressure Advance", 2022) model the extruder as
  // this first-order lag and ("Nozzle Back-Pressure, Speed and Pressure Advance", 2023) measure
  // the advance constant changing with the extrusion speed. The defaults: tau = 0.026 s at a
  // 2.25 mm/s feed (5.4 mm^3/s: a 60 mm/s line of 0.45 x 0.2 mm, the profile's print settings),
  // b = -0.5 (a power-law index of 0.5, as the physics model's) and a dead time of 0.02 s, half of
  // Bellini's (the filament path of a direct drive is short). The advance that holds the stored
  // melt volume at that flow, tau / (1 + b) = 0.052 s, is then the bundled example configurations'
  // hand-tuned 0.05 s.
  double K_N_per_mm_s = 3.5;
  double tau_s = 0.026;             ///< s, the time constant at tau_ref_feed_mm_s
  double tau_ref_feed_mm_s = 2.25;  ///< mm/s of filament, the feed tau_s is given at
  double tau_flow_exponent = -0.5;  ///< b of tau(u) = tau_s (u / tau_ref_feed_mm_s)^b; 0: tau does not change
  double theta_s = 0.02;
  /// The time constant of the FOPDT liquefier driven at `feed_mm_s` (filament mm/s).
  double tau_at_feed(double feed_mm_s) const;
  // Physics: pressure P (MPa) in the melt, flow out Q = (P / k)^(1/n) (mm^3/s, power-law melt
  // through the nozzle), column + melt compliance C (mm^3/MPa): C dP/dt = A u(t - theta) - Q;
  // force = P * A (A filament cross-section, mm^2). K = n F / u and tau = C k n Q^(n-1)
  // depend on the flow.
  double k_MPa = 2.7;  ///< MPa (s/mm^3)^n
  double n_index = 0.5;
  double compliance_mm3_MPa = 0.5;
  double filament_diameter_mm = 1.75;
  double force_offset_N = 0.5;
  double force_noise_N = 0.02;
  double load_cell_rate_hz = 200;  ///< the converter's nominal rate (Hz)
  /// The converter's clock runs on its own oscillator, this fraction fast (negative: slow): its
  /// samples slide along the planner's moves as a real converter's do. 0 locks a nominal rate
  /// that divides a staircase's move time onto the moves' junctions.
  double load_cell_clock_error = 0.0025;
  // Axes.
  std::map<std::string, std::vector<SimMode>> modes{{"x", {{48, 0.08, 1}}}, {"y", {{42, 0.09, 1}}}};
  /// The bed of a bed slinger: the axis that carries it (bed_axis, "x" or "y"), its effective
  /// moving mass m0 (bed, carriage and the belt's share, as its first mode sees them) and a load
  /// m placed on it (kg). The axis' first mode in `modes` is the empty bed's: its frequency f0 and
  /// damping ratio z0 set the axis' stiffness k = m0 (2 pi f0)^2 and viscous damping
  /// c = 2 z0 sqrt(k m0); with the load the mode runs at f = (1/2 pi) sqrt(k / (m0 + m)) with
  /// zeta = c / (2 sqrt(k (m0 + m))) (loaded_modes()). Options "bed_axis=y",
  /// "bed_moving_mass_kg=1", "bed_load_kg=0.3"; the load's place on the bed is recorded only.
  std::string bed_axis = "y";
  double bed_moving_mass_kg = 1.0;
  double bed_load_kg = 0;
  /// The bed axis' stiffness k (N/m) from its empty-bed mode and moving mass.
  double bed_stiffness_N_per_m() const;
  /// `modes` with the bed axis' first mode moved by the load (the modes the plant runs).
  std::map<std::string, std::vector<SimMode>> loaded_modes() const;
  double accel_rate_hz = 3200;
  double accel_noise_mm_s2 = 20;
  double cross_coupling = 0.05;  ///< share of one horizontal axis' response seen on the other
  double jerk_mm_s3 = 1e8;
  /// Input shaping of the commanded x/y motion, as the firmware applies it: the commanded
  /// acceleration becomes sum_i A_i a(t - T_i) (impulses rounded to the simulation step).
  /// Option "shaper_x=TYPE:FREQ_HZ[:DAMPING]" (damping default 0.1), e.g. "shaper_x=zv:48".
  std::map<std::string, std::vector<std::pair<double, double>>> shapers;  ///< axis -> (A_i, T_i s)
  std::map<std::string, std::string> shaper_names;                        ///< axis -> "zv:48:0.1"
  unsigned seed = 1;
  /// The hot end's thermal plant (thermal_plant.hpp). Options: "hot_end=drawn" draws it from the
  /// seed (draw_thermal_plant), then "heater_power_w=", "block_heat_capacity_j_per_k=",
  /// "sensor_responsiveness_per_s=", "ambient_transfer_w_per_k=", "fan_transfer_w_per_k=",
  /// "filament_heat_capacity_j_per_k_mm=", "ambient_c=", "fan_exponent=", "thermistor_noise_c=",
  /// "adc_step_c=" set single values.
  ThermalPlantTruth hot_end;
  // The firmware whose planner rules the simulator follows ("marlin", "klipper", "rrf"): M115
  // names it, and moves run as that firmware plans them:
  //   Klipper: every extrude-only move stops at both ends (toolhead.py Move.calc_junction) and
  //     is accelerated at min(ACCEL, max_extrude_only_accel); longer than
  //     max_extrude_only_distance it is refused ("!! Extrude only move too long"); a move's peak
  //     speed is capped by minimum_cruise_ratio (toolhead.py flush: v^2 <= a L (1 - mcr)),
  //     SET_VELOCITY_LIMIT MINIMUM_CRUISE_RATIO= sets it.
  //   Marlin: moves with fewer than MIN_STEPS_PER_SEGMENT (6) steps are joined with the next
  //     (planner.cpp); a move shorter than M205 B (us, default 20000) is slowed to last that
  //     long; M204 is capped by M201 (default X/Y 3000); extrude-only moves use M204 R.
  //   RepRapFirmware: a reversal is joined at M566/2 (DDA.cpp MatchSpeeds); M204 applies to XY
  //     moves only, extrude-only moves use M201 E; M410 is not an RRF command.
  std::string firmware = "marlin";
  double steps_per_mm = 160;                   ///< X/Y steps per mm (M92; the built-in profile's)
  double max_extrude_only_distance_mm = 50;    ///< Klipper [extruder] max_extrude_only_distance
  double max_extrude_only_accel_mm_s2 = 5000;  ///< Klipper [extruder] max_extrude_only_accel
  double minimum_cruise_ratio = 0.5;           ///< Klipper [printer] minimum_cruise_ratio
  /// Marlin and RepRapFirmware: the acceleration limits in force at start (M201 X/Y, M204 R and
  /// M201 E, mm/s^2), as the firmware's configuration sets them; 0 takes the firmware's default
  /// (sim_constants.hpp: Marlin's Configuration.h, a typical RepRapFirmware config.g).
  double max_accel_xy_mm_s2 = 0;
  double retract_accel_mm_s2 = 0;
  double max_accel_e_mm_s2 = 0;
  /// Whether M115 offers tunekit's sensor stream (Cap:TUNEKIT_SENSOR_STREAM:1); off, the
  /// simulator is a firmware that cannot stream its sensors over the G-code link.
  bool sensor_stream = true;
  /// Marlin only: built with AUTO_REPORT_TEMPERATURES (M115 "Cap:AUTOREPORT_TEMP:1", M155
  /// auto-reports); off, M155 is an unknown command.
  bool autoreport_temp = true;
  /// Marlin only: the build's FT_MOTION (fixed-time motion, M493): "none" (not built: M493 is
  /// an unknown command), "off" (built, M493 S0) or "on" (built and active, M493 S1). M493
  /// answers as Marlin/src/gcode/feature/ft_motion/M493.cpp does (say_shaping()).
  std::string ft_motion = "none";
  /// Marlin only: which form of M493 the FT_MOTION build speaks (firmware/marlin_m493.hpp):
  /// "mode" (2023: one mode S10..S15 for X and Y), "axis_slash" (2024: "with X/A axis ..."),
  /// "axis_named" (2024-2025: "with X axis ..."), "axis_list" (2025: "(X=ZV ; Y=MZV)" with
  /// X/Y<shaper> letters) or "axis_list_v2" (the same report with "None" for unshaped axes,
  /// C<shaper> for the axes flagged X/Y, and "FTM V2" in answer to M493 V).
  std::string m493_form = "axis_named";
  /// The build's FT_MOTION shaper per axis at start (ftMotionShaper_t code, 0 none .. 8 MZV)
  /// and its base frequency, Hz ("ft_shaper_x=1:41").
  int ft_shaper[2] = {0, 0};
  double ft_freq_hz[2] = {37, 37};
  /// RepRapFirmware only ("rrf_http=1"): the board's web server on 127.0.0.1 (an ephemeral
  /// port), serving rr_download of the files M956 writes, as src/Networking/HttpResponder.cpp
  /// does. M955 P0 reports the accelerometer and M956 P0 S<n> A<m> [F"name"] records n samples
  /// into 0:/sys/accelerometer/ (src/Accelerometers/Accelerometers.cpp) in either case.
  bool rrf_http = false;
  /// The board's web server password (M551, "rrf_password=WORD"); empty or "reprap" (RepRap.cpp
  /// NoPasswordSet): none, any request opens a session. Otherwise a client must log in with
  /// rr_connect first. The simulated board's own setting: it is not written into truth.json.
  std::string rrf_password;
  /// How many HTTP sessions the board holds at once ("rrf_http_sessions=N"; M122 "HTTP sessions:
  /// n of 8"); rr_connect answers {"err":2} beyond.
  int rrf_http_sessions = 8;
  std::vector<SimFault> faults;

  /// "key=value" options (tunekit-sim flags and `tunekit run --sim`), e.g. "preset=peek", "tau_s=0.5",
  /// "firmware=klipper", "steps_per_mm=160",
  /// "liquefier=physics", "mode_x=48:0.08" or "mode_x=48:0.08:0.7,95:0.05:0.3",
  /// "fault=garble@12", "fault=late-ok@12:300", "fault=drop@12", "fault=disconnect@40",
  /// "fault=error@30", "seed=3", "bed_load_kg=0.3". InputError for unknown keys or bad values.
  static SimConfig from_options(const std::vector<std::string>& options);
  /// from_options' last step: "hot_end=drawn" draws the hot end from the seed (whatever the
  /// options' order), the single hot-end values given beside it then set.
  static SimConfig with_hot_end_drawn(SimConfig c, const std::vector<std::string>& options);
  /// The simulated printer a machine profile describes: its firmware's planner rules
  /// ([machine] firmware; prusa runs Marlin's, kalico Klipper's), X/Y steps per mm, the
  /// extruder's extrude-only acceleration and longest move, Klipper's minimum cruise ratio, the
  /// firmware's acceleration limits ([firmware_state]) and the accelerometer's rate; then
  /// `options` (from_options' keys), which win over the profile.
  static SimConfig for_machine(const machine::MachineProfile& profile, const std::vector<std::string>& options);
  /// The from_options keys for_machine derives from a profile ("firmware=klipper", ...).
  static std::vector<std::string> machine_options(const machine::MachineProfile& profile);
  /// Marlin and RepRapFirmware: the G-code that sets the acceleration limits in force at start
  /// (M201, and Marlin's M204 R); empty for Klipper.
  std::vector<std::string> acceleration_gcode() const;
  /// The truth the simulator runs with (also written to truth.json).
  nlohmann::json truth() const;
  /// The defaults of a preset (SimPreset), and its option name ("desktop", "peek").
  static SimConfig with_preset(SimPreset preset);
  static const char* preset_name(SimPreset preset);
};

class Simulator {
 public:
  explicit Simulator(SimConfig config);
  using Emit = std::function<void(std::string_view)>;

  /// Handles one received line; writes answers and sensor data through `emit` (complete lines).
  /// Returns false when a disconnect fault fires (the caller drops the connection).
  bool handle_line(std::string_view raw, const Emit& emit);
  /// A late answer (fault late-ok) stops waiting as soon as `*cancel` is set: the host that
  /// gave up and stops the simulator is not kept waiting for it. serve_simulator() passes its
  /// stop flag; nullptr waits the whole delay.
  void set_cancel(const std::atomic<bool>* cancel) { cancel_ = cancel; }

  /// One piece of a step's commanded acceleration along the move's path: h_s seconds of
  /// accel_mm_s2 + jerk_mm_s3 * s.
  struct PathPiece {
    double h_s, accel_mm_s2, jerk_mm_s3;
  };

  /// For Klipper-API style use: samples go to this callback instead of echo:TKA lines.
  std::function<void(double t_s, double ax, double ay, double az)> accel_sink;
  /// Klipper-API style: load-cell samples (force in N, offset and noise included) go here
  /// instead of echo:TKL lines.
  std::function<void(double t_s, double force_N)> load_cell_sink;
  /// Every executed move: its start (machine time, s), the time it ran (s, a whole number of
  /// simulation steps), its velocity profile along the path, start position and unit direction
  /// (X, Y, Z, E). A fake Klipper server turns these into motion_report/dump_trapq rows.
  std::function<void(double t0_s, double duration_s, const machine::Profile& profile,
                     const std::array<double, 4>& start, const std::array<double, 4>& unit)>
      move_sink;
  /// Every simulation step: the nozzle position (X, Y, Z, E; mm), its XY speed (mm/s) and the
  /// flow leaving the nozzle (mm^3/s, the simulated liquefier's output; never negative). The
  /// simulated camera (sim_camera.hpp) lays the printed bead down from these.
  std::function<void(double t_s, const std::array<double, 4>& pos, double speed_xy_mm_s, double flow_out_mm3_s)>
      deposit_sink;
  void set_streaming(const std::string& sensor, bool on);
  /// Runs any queued move to completion.
  void flush(const Emit& emit);

  const SimConfig& config() const { return cfg_; }
  /// Thread-safe copies of what was received, and sample counts sent.
  std::vector<std::string> received() const;
  long accel_samples_sent() const { return accel_sent_; }
  long load_cell_samples_sent() const { return load_sent_; }
  bool halted() const { return halted_; }
  double time_s() const { return t_; }
  /// The hot end's heater loop (its target, duty and reading now); read it while the simulator
  /// is not serving.
  const SimHeater& hot_end() const { return heater_; }
  /// A file on the simulated board ("0:/sys/accelerometer/x.csv"), thread-safe; nullopt if absent.
  std::optional<std::string> file(const std::string& name) const;

 private:
  struct Pending {
    machine::GcodeMove move;
  };
  /// Runs one move; returns the speed it leaves at (mm/s).
  double execute(const machine::GcodeMove& m, double v_entry, double v_exit, const Emit& emit);
  void dwell(double seconds, const Emit& emit);
  /// One simulation step. `path` (with the move's unit direction) is the step's commanded
  /// acceleration exactly, piece by piece: the axes' modes follow it exactly where the axis is not
  /// shaped (base_excited_mode.hpp); a shaped axis, or a step without it, is integrated with the
  /// classical Runge-Kutta method from the accelerations at the step's start, middle and end.
  void step(const std::array<double, 4>& pos, const std::array<double, 4>& vel, const std::array<double, 4>& acc,
            const std::array<double, 3>& acc_mid, const std::array<double, 3>& acc_end, const Emit& emit,
            const std::vector<PathPiece>* path = nullptr, const std::array<double, 4>* unit = nullptr);
  /// The axes' modes over one step (see step()); returns the x, y, z accelerometer readings
  /// before noise and cross-coupling.
  std::array<double, 3> step_modes(const std::array<double, 4>& acc0, const std::array<double, 3>& accm,
                                   const std::array<double, 3>& acc1, const std::vector<PathPiece>* path,
                                   const std::array<double, 4>* unit);
  /// Streams the pieces of a move the simulator ran (echo:TKM lines) while the accelerometer
  /// streams.
  void stream_commanded_motion(double t_start, double t_end, double origin, const machine::Profile& prof,
                               const std::array<double, 4>& unit);
  void out_flush(const Emit& emit);

  SimConfig cfg_;
  machine::GcodeInterpreter interp_;
  std::optional<machine::GcodeMove> pending_;
  double pending_entry_ = 0;
  double step_carry_s_ = 0;                           ///< time of the last move not yet run as a step, s (< one step)
  std::optional<std::array<double, 4>> carry_start_;  ///< Marlin: start of a move joined with the next
  double min_segment_time_s_ = 0.020;                 ///< Marlin M205 B
  double jerk_x_mm_s_ = 15, jerk_y_mm_s_ = 15;        ///< RRF M566
  double mcr_ = 0.5;                                  ///< Klipper minimum_cruise_ratio
  double junction_speed(const machine::GcodeMove& a, const machine::GcodeMove& b) const;
  // The firmware whose rules apply (SimConfig::firmware, read once when the simulator starts).
  enum class FirmwareRules { marlin, klipper, rrf };
  FirmwareRules firmware_ = FirmwareRules::marlin;
  bool klipper() const { return firmware_ == FirmwareRules::klipper; }
  bool rrf() const { return firmware_ == FirmwareRules::rrf; }
  bool queue_move(const machine::GcodeWords& words, const Emit& emit);
  void report_firmware(const Emit& emit) const;
  void m493(const machine::GcodeWords& w, const Emit& emit);
  void m493_mode(const machine::GcodeWords& w, bool& report, const Emit& emit);
  bool m493_axis_letters(const machine::GcodeWords& w, bool& report, const Emit& emit);
  void m493_flags(const machine::GcodeWords& w, bool& report, const Emit& emit);
  void m493_advance(const machine::GcodeWords& w, bool& report, const Emit& emit);
  void m493_say_shaping(const Emit& emit) const;
  void m956(std::string_view body, const machine::GcodeWords& w, const Emit& emit);
  /// handle_line's steps: a numbered line out of sequence (or M110, or one sent again) is
  /// answered here (true); the command run (false: its answer is complete, no "ok" follows);
  /// the motion limits of M205 B, M566 and SET_VELOCITY_LIMIT; the reports M115, M105, M114
  /// and the heaters' waits (same return as execute); a late "ok" waited for.
  bool answer_line_number(const machine::NumberedLine& nl, const machine::GcodeWords* words, const Emit& emit);
  bool execute(const machine::GcodeWords& w, std::string_view body, const Emit& emit);
  void set_motion_limits(const machine::GcodeWords& w);
  bool answer_report(const machine::GcodeWords& w, const Emit& emit);
  void wait_late(double late_ms) const;
  bool marlin() const { return firmware_ == FirmwareRules::marlin; }
  /// Applies the faults planned for the line just received (sim_faults.cpp): may corrupt `line`
  /// or set `late_ms`; a value means handle_line returns it at once.
  std::optional<bool> inject_faults(std::string& line, double& late_ms, const Emit& emit);
  long received_count_ = 0;
  const std::atomic<bool>* cancel_ = nullptr;
  long last_n_ = 0;
  bool halted_ = false;
  // Marlin FT_MOTION state (M493): active, shaper per axis (ftMotionShaper_t: 0 NONE .. 8 MZV),
  // base frequency, zeta, linear advance on/off and gain.
  bool ftm_active_ = false;
  int ftm_shaper_[2] = {0, 0};
  double ftm_freq_[2] = {37, 37};
  double ftm_zeta_[2] = {0.1, 0.1};
  bool ftm_la_ = false;
  double ftm_k_ = 0;
  bool stream_accel_ = false, stream_load_ = false, stream_heater_ = false;
  // The hot end: its heater loop, the time and filament not yet run through it (it is advanced
  // in chunks, not every simulation step), and the samples streamed so far.
  SimHeater heater_;
  double heater_dt_ = 0, heater_fed_ = 0;
  std::size_t heater_sent_ = 0;
  // M155: the auto-report's interval (0: off), the machine time of the next report, s, and the
  // heater loop's tick it last reported.
  double autoreport_s_ = 0, autoreport_next_s_ = 0;
  std::size_t autoreport_tick_ = 0;
  /// M155 S<s>, as Marlin's AutoReporter::set_interval (Marlin/src/libs/autoreport.h).
  void set_auto_report(const machine::GcodeWords& w, std::string_view body, const Emit& emit);
  /// The auto-reports due up to the hot end's time, into the output.
  void auto_report();
  /// Runs the hot end up to the simulator's time and streams its finished samples.
  void sync_heater();
  /// One simulation step of `h` s with `fed_mm` of filament: the hot end is run every chunk.
  void run_heater(double h, double fed_mm);
  /// M104, M106, M107 and M105 on the hot end; false when `w` is none of them.
  bool hot_end_command(const machine::GcodeWords& w, const Emit& emit);
  // RepRapFirmware M956 run: the file being written, samples still to take, the next number.
  std::map<std::string, std::string> files_;
  std::string capture_name_, capture_text_;
  long capture_left_ = 0, capture_index_ = 0;
  // Physics state.
  double t_ = 0;
  double dt_;
  long step_ = 0;
  int accel_every_;
  std::map<std::string, std::vector<std::array<double, 2>>> mode_state_;
  std::map<std::string, std::vector<ident::BaseExcitedMode>> mode_physics_;
  std::map<std::string, std::vector<ident::ModeStep>> mode_dt_step_;  ///< each mode's step of dt_
  // Unshaped commanded accelerations (start, middle, end of each step) of x and y, for shaping.
  std::array<std::vector<std::array<double, 3>>, 2> shape_hist_;
  std::size_t shape_pos_ = 0;
  std::vector<double> delay_;
  std::size_t delay_pos_ = 0;
  double delay_frac_ = 0;  ///< the dead time's fraction of a step beyond delay_.size() - 1 steps
  double liq_ = 0;         ///< FOPDT output (N) or pressure (MPa)
  /// The load cell's converter runs on its own clock: samples at whole periods of
  /// 1 / load_cell_rate_hz from power-up, between the simulation's steps (the force and the fed
  /// length linear over a step), not locked to the planner's grid, which a rate that divides a
  /// staircase's move time would alias onto its stops.
  /// The feed a load-cell sample reports is the mean over the sample interval centred on it (the
  /// planned extruder position's change, as Klipper's motion queue gives it), not the speed at
  /// the sample instant, which a staircase of moves that stop between them would alias. A sample
  /// waits half an interval for the second half of its window: the filament fed (mm) since
  /// power-up, and when and at what length the window began.
  double fed_total_mm_ = 0, fed_at_window_start_ = 0, window_start_t_ = 0;
  double next_load_t_ = 0, next_load_edge_t_ = 0, load_force_before_ = 0;
  bool load_pending_ = false;
  double pending_t_ = 0, pending_force_ = 0;
  void start_load_cell();
  double load_cell_period() const;  ///< s, on the converter's own clock
  void sample_load_cell(double h, double fed_before, double force_now);
  void emit_pending_load_sample(double t, double fed_mm);
  std::mt19937 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  std::string out_;
  std::atomic<long> accel_sent_{0}, load_sent_{0};
  mutable std::mutex mu_;
  std::vector<std::string> received_;
};

/// The simulated RepRapFirmware board's web server: GET /rr_download?name=<file> answers as
/// src/Networking/HttpResponder.cpp SendFile/RejectMessage do ("HTTP/1.1 200 OK" with
/// Content-Length and the bytes, or "HTTP/1.1 404 file not found"); sessions as its
/// GetJsonResponse/CheckAuthenticated keep them (rr_connect with SimConfig::rrf_password, the
/// X-Session-Key header, rr_disconnect, "401 Not authorized" without a session). Listens on
/// 127.0.0.1.
class SimHttpServer {
 public:
  explicit SimHttpServer(const Simulator& sim);
  ~SimHttpServer();
  SimHttpServer(const SimHttpServer&) = delete;
  SimHttpServer& operator=(const SimHttpServer&) = delete;
  std::string url() const;
  long requests() const { return requests_; }
  /// Every request target received, in order (what a test checks the client sent).
  std::vector<std::string> targets() const;

 private:
  void serve();
  std::string answer(const std::string& target, const std::string& request);
  std::string connect(const std::map<std::string, std::string>& query);
  const Simulator& sim_;
  std::set<std::uint32_t> sessions_;  // session keys; 0: the client's address
  std::uint32_t next_key_ = 0x2f5a0001;
  mutable std::mutex targets_mu_;
  std::vector<std::string> targets_;
  int listen_fd_ = -1;
  int port_ = 0;
  std::atomic<bool> stop_{false};
  std::atomic<long> requests_{0};
  std::thread thread_;
};

/// Serves a Simulator on a pseudo-terminal in a background thread.
class SimPtyServer {
 public:
  /// `setup` (optional) is called with the simulator before the serving thread starts
  /// (to attach sinks such as Simulator::deposit_sink without a race).
  explicit SimPtyServer(SimConfig config, const std::function<void(Simulator&)>& setup = {});
  ~SimPtyServer();
  SimPtyServer(const SimPtyServer&) = delete;
  SimPtyServer& operator=(const SimPtyServer&) = delete;
  /// The slave device to open (e.g. /dev/pts/7).
  const std::string& path() const { return slave_path_; }
  /// Stops the thread (idempotent).
  void stop();
  /// Blocks until the serving thread ends (disconnect fault, or stop()).
  void wait();
  bool disconnected() const { return disconnected_; }
  Simulator& sim() { return *sim_; }
  /// "http://127.0.0.1:PORT" of the simulated board's web server (SimConfig::rrf_http); empty without.
  std::string http_url() const;
  /// The request targets the board's web server received, in order (empty without one).
  std::vector<std::string> http_targets() const;

 private:
  void serve();
  std::unique_ptr<Simulator> sim_;
  std::unique_ptr<SimHttpServer> http_;
  int master_ = -1;
  int slave_keepalive_ = -1;
  std::string slave_path_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> disconnected_{false};
  std::thread thread_;
};

/// Serves a Simulator on an already connected transport until `stop` is set or the peer goes.
void serve_simulator(Simulator& sim, machine::Transport& t, const std::atomic<bool>& stop);

}  // namespace tunekit::sim
