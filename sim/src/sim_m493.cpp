// The simulated Marlin's M493 (fixed-time motion, Marlin/src/gcode/feature/ft_motion/M493.cpp) in
// the form of the build chosen by SimConfig::m493_form, on a build with X and Y shaping and
// without HAS_DYNAMIC_FREQ. Without parameters, or after a change that sets flag.report, M493
// prints say_shaping() as that source did; a build without FT_MOTION answers as gcode.cpp does
// for any unknown command.
#include <string>

#include <fmt/format.h>

#include "sim_constants.hpp"
#include "tunekit/sim/simulator.hpp"

namespace tunekit::sim {
namespace {

// say_shaping()'s names of ftMotionShaper_t 0..8 (Marlin/src/module/ft_types.h).
const char* const kNames[] = {"None", "ZV", "ZVD", "ZVDD", "ZVDDD", "EI", "2 Hump EI", "3 Hump EI", "MZV"};

// The 2023 form's ftMotionMode_t: S10 ZV, S11 ZVD, S12 EI, S13 2HEI, S14 3HEI, S15 MZV (one
// mode for X and Y; S0 standard motion, S1 fixed-time without shaping).
struct ModeShaper {
  int mode, shaper;
};
constexpr ModeShaper kModes[] = {{10, 1}, {11, 2}, {12, 5}, {13, 6}, {14, 7}, {15, 8}};

}  // namespace

void Simulator::m493(const machine::GcodeWords& w, const Emit& emit) {
  if (cfg_.ft_motion == "none") {
    emit("echo:Unknown command: \"M493\"\n");
    return;
  }
  const std::string& form = cfg_.m493_form;
  if (form == "axis_list_v2" && w.has("V") && w.args.size() == 1) {
    emit("FTM V2\n");  // FTM_VERSION (Marlin/src/module/ft_motion.h)
    return;
  }
  bool report = w.args.empty();
  if (form == "mode") m493_mode(w, report, emit);
  else if (form == "axis_list_v2") m493_flags(w, report, emit);
  else if (!m493_axis_letters(w, report, emit)) return;
  if (form != "axis_list_v2") m493_advance(w, report, emit);
  if (report) m493_say_shaping(emit);
}

// 2023: S<mode> sets fixed-time motion and the one shaper of X and Y; A/B need a shaping mode.
void Simulator::m493_mode(const machine::GcodeWords& w, bool& report, const Emit& emit) {
  if (w.has("S")) {
    const int m = static_cast<int>(w.get("S", 0));
    int shaper = -1;
    if (m == 0 || m == 1) shaper = 0;
    for (const auto& k : kModes)
      if (k.mode == m) shaper = k.shaper;
    if (shaper < 0) {
      emit("?Invalid control mode [M] value.\n");
      return;
    }
    ftm_active_ = m != 0;
    ftm_shaper_[0] = ftm_shaper_[1] = shaper;
    report = true;
  }
  for (int a = 0; a < 2; ++a) {
    const std::string f = a == 0 ? "A" : "B";
    if (!w.has(f)) continue;
    if (ftm_shaper_[a] == 0) {
      emit(fmt::format("Wrong mode for [{}] frequency.\n", f));
      continue;
    }
    ftm_freq_[a] = w.get(f, ftm_freq_[a]);
    report = true;
  }
}

// 2024-2025: S on/off, X/Y<shaper>, A/B base frequency and I/J zeta (both need a shaper on the
// axis). False when a shaper value is invalid (M493 returns at once).
bool Simulator::m493_axis_letters(const machine::GcodeWords& w, bool& report, const Emit& emit) {
  if (w.has("S")) {
    const bool on = w.get("S", 0) != 0;
    if (on != ftm_active_) report = true;
    ftm_active_ = on;
  }
  for (int a = 0; a < 2; ++a) {
    const std::string letter = a == 0 ? "X" : "Y";
    if (!w.has(letter)) continue;
    const int sh = static_cast<int>(w.get(letter, 0));
    if (sh < 0 || sh > sim::kFtmLastShaper) {
      emit(fmt::format("?Invalid [{}] shaper.\n", letter));
      return false;
    }
    if (sh != ftm_shaper_[a]) report = true;
    ftm_shaper_[a] = sh;
  }
  for (int a = 0; a < 2; ++a) {
    const std::string f = a == 0 ? "A" : "B", z = a == 0 ? "I" : "J";
    if (w.has(f)) {
      if (ftm_shaper_[a] == 0) emit(fmt::format("Wrong mode for [{}] frequency.\n", f));
      else {
        ftm_freq_[a] = w.get(f, ftm_freq_[a]);
        report = true;
      }
    }
    if (w.has(z) && ftm_shaper_[a] != 0) ftm_zeta_[a] = w.get(z, ftm_zeta_[a]);
  }
  return true;
}

// From late 2025: C<shaper>, A<Hz> and I<zeta> apply to the axes flagged X/Y (neither: both).
void Simulator::m493_flags(const machine::GcodeWords& w, bool& report, const Emit& emit) {
  if (w.has("S")) {
    const bool on = w.get("S", 0) != 0;
    if (on != ftm_active_) report = true;
    ftm_active_ = on;
  }
  const bool seen_c = w.has("C");
  const int c = static_cast<int>(w.get("C", 0));
  if (seen_c && (c < 0 || c > sim::kFtmLastShaper)) {
    emit(fmt::format("?Invalid (C)ompensator value. (0-{})\n", sim::kFtmLastShaper));
    return;
  }
  const bool both = !w.has("X") && !w.has("Y") && !w.has("Z") && !w.has("E");
  for (int a = 0; a < 2; ++a) {
    const char name = a == 0 ? 'X' : 'Y';
    if (!both && !w.has(std::string(1, name))) continue;
    if (seen_c && c != ftm_shaper_[a]) {
      ftm_shaper_[a] = c;
      report = true;
    }
    if (w.has("A")) {
      if (ftm_shaper_[a] == 0) emit(fmt::format("?Wrong mode for {} (A) frequency.\n", name));
      else if (w.get("A", 0) != ftm_freq_[a]) {
        ftm_freq_[a] = w.get("A", 0);
        report = true;
      }
    }
    if (w.has("I") && ftm_shaper_[a] != 0) ftm_zeta_[a] = w.get("I", ftm_zeta_[a]);
  }
}

// P linear advance on/off, K its gain (the forms before late 2025).
void Simulator::m493_advance(const machine::GcodeWords& w, bool& report, const Emit& emit) {
  if (w.has("P")) {
    ftm_la_ = w.get("P", 0) != 0;
    report = true;
    emit(ftm_la_ ? "Linear Advance enabled.\n" : "Linear Advance disabled.\n");
  }
  if (w.has("K")) {
    const double k = w.get("K", 0);
    if (k >= 0) {
      ftm_k_ = k;
      report = true;
    } else {
      emit("Linear Advance gain out of range.\n");
    }
  }
}

void Simulator::m493_say_shaping(const Emit& emit) const {
  const std::string& form = cfg_.m493_form;
  const bool shaping = ftm_shaper_[0] != 0 || ftm_shaper_[1] != 0;
  std::string l = fmt::format("Fixed-Time Motion {}abled", ftm_active_ ? "en" : "dis");
  if (form == "mode") {
    if (ftm_shaper_[0]) l += fmt::format(" with {} shaping", kNames[ftm_shaper_[0]]);
  } else if (form == "axis_slash" || form == "axis_named") {
    const bool slash = form == "axis_slash";
    if (ftm_shaper_[0]) l += fmt::format(" with {} axis {} shaping", slash ? "X/A" : "X", kNames[ftm_shaper_[0]]);
    if (ftm_shaper_[1]) l += fmt::format(" and with {} axis {} shaping", slash ? "Y/B" : "Y", kNames[ftm_shaper_[1]]);
  } else if (shaping) {
    const bool v2 = form == "axis_list_v2";
    std::string items;
    for (int a = 0; a < 2; ++a)
      if (v2 || ftm_shaper_[a])
        items += fmt::format("{}{}={}", items.empty() ? "" : " ; ", a == 0 ? 'X' : 'Y', kNames[ftm_shaper_[a]]);
    l += " (" + items + ")";
  }
  const bool list = form == "axis_list" || form == "axis_list_v2";
  emit(l + (list ? "\n" : ".\n"));
  if (form == "axis_list_v2") {
    if (ftm_active_) emit("Axis Sync. enabled\n");
    for (int a = 0; a < 2; ++a)
      if (ftm_shaper_[a])
        emit(fmt::format("{} static shaper frequency: {:.2f} Hz\n", a == 0 ? 'X' : 'Y', ftm_freq_[a]));
    return;
  }
  if (shaping) {
    const bool old = form == "mode" || form == "axis_slash";
    emit(fmt::format("{} static {} frequency: {:.2f}Hz\n", old ? "X/A" : "X", old ? "compensator" : "shaper",
                     ftm_freq_[0]));
    emit(fmt::format("{} static {} frequency: {:.2f} Hz\n", old ? "Y/B" : "Y", old ? "compensator" : "shaper",
                     ftm_freq_[1]));
  }
  if (form == "mode") emit(fmt::format("Linear Advance {}abled. Gain: {:.5f}\n", ftm_la_ ? "en" : "dis", ftm_k_));
  else if (form == "axis_list" && !ftm_active_) return;
  else if (form == "axis_list")
    emit(fmt::format("Linear Advance {}abled. Gain: {:.2f}\n", ftm_la_ ? "en" : "dis", ftm_k_));
  else emit(ftm_la_ ? fmt::format("Linear Advance enabled. Gain: {:.2f}\n", ftm_k_) : "Linear Advance disabled\n");
}

}  // namespace tunekit::sim
