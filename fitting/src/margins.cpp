#include "tunekit/fitting/margins.hpp"

#include <cmath>

namespace tunekit::fitting {
namespace {

// The kind of a quantity: the last part of its name ("x.freq_hz" -> "freq_hz").
std::string margin_kind_of(const std::string& name) {
  const auto dot = name.rfind('.');
  return dot == std::string::npos ? name : name.substr(dot + 1);
}

// The axis or prefix of a quantity: "x.shaper_freq_hz" -> "x."; "" when there is none.
std::string margin_prefix_of(const std::string& name) {
  const auto dot = name.rfind('.');
  return dot == std::string::npos ? std::string() : name.substr(0, dot + 1);
}

Margin measured(std::string kind, double relative, std::string basis) {
  return {std::move(kind), relative, false, std::move(basis), {}};
}

Margin designed(std::vector<std::string> from) {
  return {"designed", 0, true, "designed from other quantities; it drifts only through them", std::move(from)};
}

}  // namespace

Margin equivalence_margin(const std::string& name) {
  const std::string k = margin_kind_of(name), pre = margin_prefix_of(name);
  if (k == "tau_s")
    return measured("time constant", 0.02,
                    "the advance is set to tau, so a 2 % change of tau leaves 2 % of the uncompensated pressure lag "
                    "at a speed change");
  if (k == "theta_s")
    return measured("dead time", 0.05,
                    "the advance cannot remove the dead time; 5 % of it shifts where a line starts by well under "
                    "a nozzle width");
  if (k == "K")
    return measured("gain", 0.02, "a 2 % change of the liquefier's gain is a step of a slicer's flow-rate calibration");
  if (k == "freq_hz")
    return measured("resonance frequency", 0.01,
                    "a 1 % error in the frequency leaves a ZV shaper, the least robust, 1.4 % of the unshaped "
                    "vibration");
  if (k == "zeta")
    return measured("damping ratio", 0.10,
                    "a 10 % error in the damping ratio leaves a ZV shaper 1.1-1.4 % of the unshaped vibration, "
                    "as a 1 % error in the frequency does");
  if (k.find("tension") != std::string::npos)
    return measured("belt tension", 0.02,
                    "the resonance frequency goes as the square root of the tension: 2 % of tension is the 1 % "
                    "of frequency a shaper tolerates");
  if (k == "shaper" || k == "shaper_freq_hz" || k == "max_accel_mm_s2")
    return designed({pre + "freq_hz", pre + "zeta"});
  if (k == "pa_k_s") return designed({"tau_s", "freq.tau_s", "record.tau_s", "freq.record.tau_s"});
  if (k == "pa_smooth_s")
    return designed({"tau_s", "theta_s", "freq.tau_s", "record.tau_s", "record.theta_s", "freq.record.tau_s"});
  return measured("other", 0.05, "a quantity of no known kind: 5 %");
}

int beyond_margin(double difference, double half_width, double margin) {
  const double d = std::fabs(difference), h = std::fabs(half_width), m = std::fabs(margin);
  if (d - h > m) return 1;
  if (d + h < m) return -1;
  return 0;
}

}  // namespace tunekit::fitting
