#include "tunekit/design/shaper_defs.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/core/text.hpp"

namespace tunekit::design {
namespace {

void normalize(Shaper& s) {
  double sum = 0;
  for (double a : s.amplitudes) sum += a;
  for (double& a : s.amplitudes) a /= sum;
}

const std::vector<ShaperInfo>& infos() {
  // Minimum frequencies as Klipper chose them (projected max_accel about 1500 mm/s^2); ZVDD,
  // which Klipper does not define, gets the 2-hump EI value (same duration, 1.5 periods).
  static const std::vector<ShaperInfo> v = {{ShaperType::zv, 21.0, 0.99},          {ShaperType::mzv, 23.0, 0.99},
                                            {ShaperType::zvd, 29.0, 0.99},         {ShaperType::zvdd, 39.0, 0.99},
                                            {ShaperType::ei, 29.0, 0.4},           {ShaperType::two_hump_ei, 39.0, 0.3},
                                            {ShaperType::three_hump_ei, 48.0, 0.2}};
  return v;
}

}  // namespace

std::string to_string(ShaperType t) {
  switch (t) {
    case ShaperType::zv: return "zv";
    case ShaperType::mzv: return "mzv";
    case ShaperType::zvd: return "zvd";
    case ShaperType::zvdd: return "zvdd";
    case ShaperType::ei: return "ei";
    case ShaperType::two_hump_ei: return "2hump_ei";
    case ShaperType::three_hump_ei: return "3hump_ei";
  }
  return "?";
}

ShaperType parse_shaper_type(const std::string& name) {
  for (const auto& i : infos())
    if (core::iequals(name, to_string(i.type))) return i.type;
  throw InputError("unknown shaper '" + name + "' (zv, mzv, zvd, zvdd, ei, 2hump_ei, 3hump_ei)");
}

const std::vector<ShaperType>& all_shaper_types() {
  static const std::vector<ShaperType> v = {ShaperType::zv,           ShaperType::mzv, ShaperType::zvd,
                                            ShaperType::zvdd,         ShaperType::ei,  ShaperType::two_hump_ei,
                                            ShaperType::three_hump_ei};
  return v;
}

const ShaperInfo& shaper_info(ShaperType t) {
  for (const auto& i : infos())
    if (i.type == t) return i;
  return infos().front();
}

namespace {

// Singhose's fits of the damped EI family (Singhose, Seering and Singer 1997), coefficients of
// 1, z, z^2, z^3 per impulse: times in periods of the undamped frequency, amplitudes as they are
// (normalized afterwards). The values are the published ones, as Klipper tabulates them.
struct HumpFit {
  std::vector<std::array<double, 4>> times, amplitudes;
};
const HumpFit& two_hump_fit() {
  static const HumpFit f{{{0, 0, 0, 0},
                          {0.49890, 0.16270, -0.54262, 6.16180},
                          {0.99748, 0.18382, -1.58270, 8.17120},
                          {1.49920, -0.09297, -0.28338, 1.85710}},
                         {{0.16054, 0.76699, 2.26560, -1.22750},
                          {0.33911, 0.45081, -2.58080, 1.73650},
                          {0.34089, -0.61533, -0.68765, 0.42261},
                          {0.15997, -0.60246, 1.00280, -0.93145}}};
  return f;
}
const HumpFit& three_hump_fit() {
  static const HumpFit f{{{0, 0, 0, 0},
                          {0.49974, 0.23834, 0.44559, 12.4720},
                          {0.99849, 0.29808, -2.36460, 23.3990},
                          {1.49870, 0.10306, -2.01390, 17.0320},
                          {1.99960, -0.28231, 0.61536, 5.40450}},
                         {{0.11275, 0.76632, 3.29160, -1.44380},
                          {0.23698, 0.61164, -2.57850, 4.85220},
                          {0.30008, -0.19062, -2.14560, 0.13744},
                          {0.23775, -0.73297, 0.46885, -2.08650},
                          {0.11244, -0.45439, 0.96382, -1.46000}}};
  return f;
}
double cubic_in(const std::array<double, 4>& c, double z) { return c[0] + z * (c[1] + z * (c[2] + z * c[3])); }

void apply_hump_fit(Shaper& s, const HumpFit& fit, double f, double z) {
  for (std::size_t i = 0; i < fit.times.size(); ++i) {
    s.times_s.push_back(cubic_in(fit.times[i], z) / f);
    s.amplitudes.push_back(cubic_in(fit.amplitudes[i], z));
  }
}

// Singhose's damped EI fit in the tolerance V and the damping ratio z (Singhose, Seering and
// Singer 1997): three impulses at 0, t2 and one damped period.
void apply_ei_fit(Shaper& s, double V, double z, double td) {
  const double a1 = (0.24968 + 0.24961 * V) + z * ((0.80008 + 1.23328 * V) + z * (0.49599 + 3.17316 * V));
  const double a3 = (0.25149 + 0.21474 * V) + z * ((-0.83249 + 1.41498 * V) + z * (0.85181 - 4.90094 * V));
  const double t2 = 0.4999 + z * ((0.46159 + 8.57843 * V) * V +
                                  z * ((4.26169 - 108.644 * V) * V + z * ((1.75601 + 336.989 * V) * V)));
  s.amplitudes = {a1, 1 - a1 - a3, a3};
  s.times_s = {0, t2 * td, td};
}

}  // namespace

Shaper design_shaper(ShaperType type, double f, double z, double V, EiDesign ei_design) {
  if (!(f > 0) || !std::isfinite(f)) throw InputError(fmt::format("shaper frequency {} Hz must be positive", f));
  if (!(z >= 0 && z < 1)) throw InputError(fmt::format("damping ratio {} must be in [0, 1)", z));
  const bool hump = type == ShaperType::two_hump_ei || type == ShaperType::three_hump_ei;
  if (ei_design == EiDesign::damped_fit && hump && std::abs(V - kDefaultVibrationTolerance) > 1e-12)
    throw InputError(fmt::format("the damped {} fit exists for a vibration tolerance of 5 % only, not {} %",
                                 to_string(type), 100 * V));
  Shaper s;
  s.type = type;
  s.freq_hz = f;
  s.damping_ratio = z;
  const double df = std::sqrt(1 - z * z);
  const double K = std::exp(-z * std::numbers::pi / df);  // decay over half a damped period
  const double td = 1.0 / (f * df);                       // damped period
  switch (type) {
    case ShaperType::zv:  // Singer & Seering: zero vibration at (f, z)
      s.amplitudes = {1, K};
      s.times_s = {0, 0.5 * td};
      break;
    case ShaperType::zvd:  // plus zero derivative in frequency
      s.amplitudes = {1, 2 * K, K * K};
      s.times_s = {0, 0.5 * td, td};
      break;
    case ShaperType::zvdd:  // plus zero second derivative
      s.amplitudes = {1, 3 * K, 3 * K * K, K * K * K};
      s.times_s = {0, 0.5 * td, td, 1.5 * td};
      break;
    case ShaperType::mzv: {  // Klipper's modified ZV: impulses 3/8 of a period apart
      const double k = std::exp(-0.75 * z * std::numbers::pi / df);
      const double a1 = 1 - 1 / std::numbers::sqrt2;
      s.amplitudes = {a1, (std::numbers::sqrt2 - 1) * k, a1 * k * k};
      s.times_s = {0, 0.375 * td, 0.75 * td};
      break;
    }
    case ShaperType::ei: {  // Singhose: V(f) = V_tol with zero slope at f; damped by the K factors
      if (ei_design == EiDesign::damped_fit) {
        apply_ei_fit(s, V, z, td);
        break;
      }
      const double a1 = 0.25 * (1 + V);
      s.amplitudes = {a1, 0.5 * (1 - V) * K, a1 * K * K};
      s.times_s = {0, 0.5 * td, td};
      break;
    }
    case ShaperType::two_hump_ei: {  // Singhose's two-hump EI closed form
      if (ei_design == EiDesign::damped_fit) {
        apply_hump_fit(s, two_hump_fit(), f, z);
        break;
      }
      const double V2 = V * V;
      const double X = std::cbrt(V2 * (std::sqrt(1 - V2) + 1));
      const double a1 = (3 * X * X + 2 * X + 3 * V2) / (16 * X);
      const double a2 = 0.5 - a1;
      s.amplitudes = {a1, a2 * K, a2 * K * K, a1 * K * K * K};
      s.times_s = {0, 0.5 * td, td, 1.5 * td};
      break;
    }
    case ShaperType::three_hump_ei: {  // Singhose's three-hump EI closed form
      if (ei_design == EiDesign::damped_fit) {
        apply_hump_fit(s, three_hump_fit(), f, z);
        break;
      }
      const double a1 = (1 + 3 * V + 2 * std::sqrt(2 * (V + 1) * V)) / 16;
      const double a2 = 0.25 * (1 - V);
      const double a3 = 0.5 * (1 + V) - 2 * a1;
      const double K2 = K * K;
      s.amplitudes = {a1, a2 * K, a3 * K2, a2 * K2 * K, a1 * K2 * K2};
      s.times_s = {0, 0.5 * td, td, 1.5 * td, 2 * td};
      break;
    }
  }
  normalize(s);
  return s;
}

}  // namespace tunekit::design
