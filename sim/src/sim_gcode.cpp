// The simulator's G-code command table: line numbers and checksums, then one branch per
// command (G0/G1 moves into the planner, G4, G28, M105, M109/M190, M114, M115, M204/M205,
// M400, M410, M112, M493 (sim_m493.cpp), M566, M955, M956, M4100, SET_VELOCITY_LIMIT), answering as the
// firmware named by SimConfig::firmware does.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <thread>

#include <fmt/format.h>

#include "sim_constants.hpp"
#include "tunekit/core/version.hpp"
#include "tunekit/sim/simulator.hpp"

namespace tunekit::sim {

// RepRapFirmware's M956 (src/Accelerometers/Accelerometers.cpp StartAccelerometer): P, S and A
// are required ("missing parameter"); X/Y/Z pick axes (all three when none is given; the
// simulated board records all three); F"name" names the file under 0:/sys/accelerometer/,
// otherwise <board>_<date>_<time>.csv; a run while one is collecting is refused.
void Simulator::m956(std::string_view body, const machine::GcodeWords& /*words*/, const Emit& emit) {
  // The quoted file name is not parameters: parse the rest.
  std::string rest(body);
  if (const auto q = rest.find('"'); q != std::string::npos) {
    const auto q2 = rest.find('"', q + 1);
    rest.erase(q, q2 == std::string::npos ? std::string::npos : q2 - q + 1);
  }
  const auto parsed = machine::parse_gcode(rest);
  const machine::GcodeWords w = parsed ? *parsed : machine::GcodeWords{};
  for (const char* k : {"P", "S", "A"})
    if (!w.has(k)) {
      emit(fmt::format("Error: M956: missing parameter '{}'\n", k));
      return;
    }
  if (capture_left_ > 0) {
    emit("Error: M956: Accelerometer is already collecting data\n");
    return;
  }
  std::string name = sim::kM956DefaultFileName;
  if (const auto f = body.find("F\""); f != std::string_view::npos) {
    const auto end = body.find('"', f + 2);
    if (end != std::string_view::npos) name = std::string(body.substr(f + 2, end - f - 2));
  }
  capture_name_ = "0:/sys/accelerometer/" + name;
  capture_left_ = std::max(1L, std::lround(w.get("S", 0)));
  capture_index_ = 0;
  capture_text_ = "Sample,X,Y,Z\n";
  std::lock_guard<std::mutex> lock(mu_);
  files_[capture_name_] = capture_text_;
}

// A G0/G1: queued behind the move before it (joined at the junction speed the firmware's rules
// give), or refused as the firmware would. False when the line is answered already.
bool Simulator::queue_move(const machine::GcodeWords& words, const Emit& emit) {
  if (auto m = interp_.apply(words)) {
    if (carry_start_) {
      m->start = *carry_start_;  // Marlin: the joined move's distance is added to this one
      carry_start_.reset();
    }
    if (klipper() && m->extruder_only() && m->length_mm() > cfg_.max_extrude_only_distance_mm) {
      out_flush(emit);
      emit(fmt::format("!! Extrude only move too long ({:.3f}mm vs {:.3f}mm)\n", m->length_mm(),
                       cfg_.max_extrude_only_distance_mm));
      emit("ok\n");
      return false;
    }
    double steps = 0;
    for (std::size_t k = 0; k < 3; ++k) steps = std::max(steps, std::abs(m->end[k] - m->start[k]) * cfg_.steps_per_mm);
    if (marlin() && !m->extruder_only() && std::lround(steps) < sim::kMarlinMinStepsPerSegment) {
      carry_start_ = m->start;  // Configuration_adv.h MIN_STEPS_PER_SEGMENT 6
    } else {
      if (pending_) {
        const double v_exit = junction_speed(*pending_, *m);
        pending_entry_ = std::min(v_exit, execute(*pending_, pending_entry_, v_exit, emit));
      }
      pending_ = *m;
    }
  }
  return true;
}

// M115: the firmware's name and capabilities, as each firmware words them.
void Simulator::report_firmware(const Emit& emit) const {
  if (klipper()) emit(fmt::format("FIRMWARE_NAME:Klipper FIRMWARE_VERSION:v0.13.0-tunekit-sim-{}\n", core::kVersion));
  else if (rrf())
    emit(
        fmt::format("FIRMWARE_NAME: RepRapFirmware for tunekit-sim FIRMWARE_VERSION: 3.5.1 ELECTRONICS: tunekit-sim "
                    "{} FIRMWARE_DATE: 2024-01-01\n",
                    core::kVersion));
  else
    emit(fmt::format(
        "FIRMWARE_NAME:Marlin 2.1.2 (tunekit-sim {}) SOURCE_CODE_URL:https://github.com/MarlinFirmware/Marlin "
        "PROTOCOL_VERSION:1.0 MACHINE_TYPE:tunekit-sim EXTRUDER_COUNT:1 "
        "UUID:00000000-0000-0000-0000-000000000000\n"
        "Cap:EEPROM:0\nCap:AUTOREPORT_TEMP:{}\n",
        core::kVersion, cfg_.autoreport_temp ? 1 : 0));
  if (cfg_.sensor_stream) emit("Cap:TUNEKIT_SENSOR_STREAM:1\n");
}

bool Simulator::answer_line_number(const machine::NumberedLine& nl, const machine::GcodeWords* words,
                                   const Emit& emit) {
  if (!nl.number) return false;
  if (words && words->command == "M110") {
    last_n_ = static_cast<long>(words->get("N", static_cast<double>(*nl.number)));
    emit("ok\n");
    return true;
  }
  if (*nl.number == last_n_) {  // a line sent again after a late ok: already done
    emit("ok\n");
    return true;
  }
  if (*nl.number != last_n_ + 1) {
    out_flush(emit);
    emit(fmt::format("Error:Line Number is not Last firmware::Line Number+1, Last firmware::Line: {}\nResend: {}\nok\n",
                     last_n_, last_n_ + 1));
    return true;
  }
  last_n_ = *nl.number;
  return false;
}

void Simulator::set_motion_limits(const machine::GcodeWords& w) {
  const std::string& c = w.command;
  if (c == "M205") {
    min_segment_time_s_ = w.get("B", sim::kMarlinDefaultMinSegmentTime_us) * sim::kSecondsPerMicrosecond;
  } else if (c == "M566") {
    if (w.has("X"))
      jerk_x_mm_s_ =
          std::max(sim::kRrfMinimumJerk_mm_s, w.get("X", sim::kRrfDefaultJerk_mm_min) / sim::kSecondsPerMinute);
    if (w.has("Y"))
      jerk_y_mm_s_ =
          std::max(sim::kRrfMinimumJerk_mm_s, w.get("Y", sim::kRrfDefaultJerk_mm_min) / sim::kSecondsPerMinute);
  } else {  // SET_VELOCITY_LIMIT
    interp_.apply(w);
    if (w.has("MINIMUM_CRUISE_RATIO")) mcr_ = w.get("MINIMUM_CRUISE_RATIO", mcr_);
  }
}

bool Simulator::hot_end_command(const machine::GcodeWords& w, const Emit& emit) {
  const std::string& c = w.command;
  if (c != "M104" && c != "M106" && c != "M107" && c != "M105") return false;
  sync_heater();
  if (c == "M104") {
    interp_.apply(w);
    heater_.set_target(interp_.hotend_c.value_or(0));
  } else if (c == "M106") {
    const double s = w.get("S", sim::kFanFullScale);
    heater_.set_fan(rrf() && s <= 1 ? s : s / sim::kFanFullScale);
  } else if (c == "M107") {
    heater_.set_fan(0);
  } else {  // M105: the hot end's reading, target and duty, the bed's target
    out_flush(emit);
    const double tb = interp_.bed_c.value_or(0);
    emit(fmt::format("ok T:{:.2f} /{:.1f} B:{:.1f} /{:.1f} @:{} B@:0\n", heater_.reading_c(), heater_.target_c(), tb,
                     tb, std::lround(heater_.duty() * sim::kMarlinPwmReportMax)));
  }
  return true;
}

void Simulator::set_auto_report(const machine::GcodeWords& w, std::string_view body, const Emit& emit) {
  if (!cfg_.autoreport_temp) {
    out_flush(emit);
    emit(fmt::format("echo:Unknown command: \"{}\"\n", body));
    return;
  }
  if (!w.has("S")) return;
  sync_heater();
  // A byte of whole seconds, at most 60; the first report one interval after the command.
  autoreport_s_ = std::clamp(std::floor(w.get("S", 0)), 0.0, sim::kMarlinAutoReportMax_s);
  autoreport_next_s_ = heater_.time_s() + autoreport_s_;
}

void Simulator::auto_report() {
  const auto& r = heater_.record();
  for (; autoreport_s_ > 0 && autoreport_next_s_ <= heater_.time_s(); autoreport_next_s_ += autoreport_s_) {
    while (autoreport_tick_ + 1 < r.t_s.size() && r.t_s[autoreport_tick_ + 1] <= autoreport_next_s_) ++autoreport_tick_;
    const bool ticked = autoreport_tick_ < r.t_s.size() && r.t_s[autoreport_tick_] <= autoreport_next_s_;
    const double reading = ticked ? r.temp_c[autoreport_tick_] : heater_.reading_c();
    const double target = ticked ? r.target_c[autoreport_tick_] : heater_.target_c();
    const double duty = ticked ? r.heater_duty[autoreport_tick_] : heater_.duty();
    const double tb = interp_.bed_c.value_or(0);
    out_ += fmt::format(" T:{:.2f} /{:.2f} B:{:.2f} /{:.2f} @:{} B@:0\n", reading, target, tb, tb,
                        std::lround(duty * sim::kMarlinPwmReportMax));
  }
}

bool Simulator::answer_report(const machine::GcodeWords& w, const Emit& emit) {
  const std::string& c = w.command;
  if (c == "M115") {
    out_flush(emit);
    report_firmware(emit);
  } else if (c == "M114") {
    flush(emit);
    const auto& p = interp_.position();
    emit(fmt::format("X:{:.3f} Y:{:.3f} Z:{:.3f} E:{:.3f} Count X:0 Y:0 Z:0\n", p[0], p[1], p[2], p[3]));
  } else {  // M109, M190
    flush(emit);
    interp_.apply(w);
    sync_heater();
    if (c == "M109") heater_.settle(interp_.hotend_c.value_or(0));  // the wait, passed at once
    const double te = interp_.hotend_c.value_or(0), tb = interp_.bed_c.value_or(0);
    emit(fmt::format(" T:{:.1f} /{:.1f} B:{:.1f} /{:.1f} @:0 B@:0\n", te, te, tb, tb));
  }
  return true;
}

bool Simulator::execute(const machine::GcodeWords& w, std::string_view body, const Emit& emit) {
  const std::string& c = w.command;
  if (c == "G0" || c == "G1") {
    if (!queue_move(w, emit)) return false;
  } else if (c == "G4") {
    flush(emit);
    interp_.apply(w);
    dwell(interp_.dwell_s(), emit);
  } else if (c == "M400") {
    flush(emit);
  } else if (c == "G28") {
    flush(emit);
    machine::GcodeWords home;
    home.command = "G92";
    for (const char* axis : {"X", "Y", "Z"}) home.args[axis] = 0;
    interp_.apply(home);
  } else if ((c == "M205" && w.has("B")) || c == "M566" || c == "SET_VELOCITY_LIMIT") {
    set_motion_limits(w);
  } else if (c == "M410" && rrf()) {
    out_flush(emit);
    emit("Error: M410: Command is not supported\n");
  } else if (c == "M410") {
    pending_.reset();  // quickstop: queued motion is dropped
    pending_entry_ = 0;
    step_carry_s_ = 0;
  } else if (c == "M112") {
    pending_.reset();
    sync_heater();
    heater_.off();      // a kill turns the heaters off (Marlin's kill(), Klipper's shutdown)
    autoreport_s_ = 0;  // and a killed Marlin reports nothing more
    halted_ = true;
    out_flush(emit);
    return false;
  } else if (hot_end_command(w, emit)) {
    return c != "M105";
  } else if (c == "M4100") {
    flush(emit);
    if (w.has("H")) set_streaming("heater", w.get("H", 0) != 0);
    if (w.has("A")) set_streaming("accelerometer", w.get("A", 0) != 0);
    if (w.has("L")) set_streaming("load_cell", w.get("L", 0) != 0);
  } else if (c == "M955" && rrf()) {
    out_flush(emit);
    // Accelerometers.cpp ConfigureAccelerometer without other parameters: the report.
    emit(
        fmt::format("Accelerometer 0 type LIS3DH with orientation 20 samples at {}Hz with 10-bit resolution, SPI "
                    "frequency 2000000\n",
                    std::lround(cfg_.accel_rate_hz)));
  } else if (c == "M956" && rrf()) {
    flush(emit);
    m956(body, w, emit);
  } else if (c == "M155" && !klipper() && !rrf()) {
    set_auto_report(w, body, emit);
  } else if (c == "M493" && !klipper() && !rrf()) {
    out_flush(emit);
    m493(w, emit);
  } else if (c == "M115" || c == "M114" || c == "M109" || c == "M190") {
    return answer_report(w, emit);
  } else {
    interp_.apply(w);
  }
  return true;
}

void Simulator::wait_late(double late_ms) const {
  // Waited in short slices, so that stopping the simulator ends the wait (set_cancel).
  using Clock = std::chrono::steady_clock;
  const Clock::time_point until =
      Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double, std::milli>(late_ms));
  while (!(cancel_ && cancel_->load()) && Clock::now() < until)
    std::this_thread::sleep_for(std::min<Clock::duration>(std::chrono::milliseconds(10), until - Clock::now()));
}

bool Simulator::handle_line(std::string_view raw, const Emit& emit) {
  std::string line(raw);
  while (!line.empty() && (line.back() == '\r' || line.back() == '\n' || line.back() == ' ')) line.pop_back();
  if (line.empty()) return true;
  ++received_count_;
  {
    std::lock_guard<std::mutex> lock(mu_);
    received_.push_back(line);
  }
  double late_ms = 0;
  if (const auto answered = inject_faults(line, late_ms, emit)) return *answered;
  if (halted_) return true;  // a killed Marlin answers nothing more
  const machine::NumberedLine nl = machine::split_numbered(line);
  if (nl.checksum && !nl.checksum_ok) {
    out_flush(emit);
    emit(fmt::format("Error:checksum mismatch, Last firmware::Line: {}\nResend: {}\nok\n", last_n_, last_n_ + 1));
    return true;
  }
  const auto words = machine::parse_gcode(nl.body);
  if (answer_line_number(nl, words ? &*words : nullptr, emit)) return true;
  if (words && !execute(*words, nl.body, emit)) return true;
  if (late_ms > 0) {
    out_flush(emit);  // what the line produced arrives on time; only its "ok" is late
    wait_late(late_ms);
  }
  // The data a line produced and its "ok" leave in one write, as from a firmware's serial
  // buffer: the host wakes once per line, not once for the data and again for the "ok".
  out_ += "ok\n";
  out_flush(emit);
  return true;
}

}  // namespace tunekit::sim
