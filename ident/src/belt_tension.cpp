#include "tunekit/ident/belt_tension.hpp"

#include <cmath>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/core/text.hpp"
#include "tunekit/fitting/stats.hpp"

namespace tunekit::ident {

const std::vector<BeltSpec>& belt_specs() {
  // 7.569 g/m at 6 mm (Prusa Research's nominal GT2 figure), in proportion to width.
  constexpr double per_mm = 7.569e-3 / 6.0;
  static const std::vector<BeltSpec> specs{{"gt2-6mm", 6, 6 * per_mm},
                                           {"gt2-9mm", 9, 9 * per_mm},
                                           {"gt2-10mm", 10, 10 * per_mm},
                                           {"gt2-12mm", 12, 12 * per_mm}};
  return specs;
}

const BeltSpec& belt_spec(const std::string& name) {
  std::string known;
  for (const auto& b : belt_specs()) {
    if (core::iequals(b.name, name)) return b;
    known += (known.empty() ? "" : ", ") + b.name;
  }
  throw InputError(fmt::format("unknown belt '{}': known are {} (or give its mass with --belt-mass-g-m)", name, known));
}

StringTension string_tension(double mu, double span_m, double span_se, double f, double f_se) {
  if (!(mu > 0) || !(span_m > 0) || !(f > 0))
    throw InputError(
        fmt::format("belt tension needs a positive mass per length, span and frequency (got {:g} kg/m, "
                    "{:g} m, {:g} Hz)",
                    mu, span_m, f));
  StringTension t;
  t.tension_n = 4 * mu * span_m * span_m * f * f;
  const double rel =
      2 * std::hypot(std::isfinite(f_se) ? f_se / f : 0.0, std::isfinite(span_se) ? span_se / span_m : 0.0);
  t.stderr_n = t.tension_n * rel;
  t.ci95_lo = t.tension_n - fitting::kZ95 * t.stderr_n;
  t.ci95_hi = t.tension_n + fitting::kZ95 * t.stderr_n;
  return t;
}

double string_frequency(double mu, double span_m, double tension_n) {
  if (!(mu > 0) || !(span_m > 0) || !(tension_n > 0)) return 0;
  return std::sqrt(tension_n / (4 * mu * span_m * span_m));
}

}  // namespace tunekit::ident
