// Fit a melt viscosity curve: the Cross model over the whole curve, a power law over the
// shear rates of a printing nozzle.
//
//   Cross      eta = eta0 / (1 + (eta0 gamma / tau*)^(1 - n))
//   power law  eta = K gamma^(n - 1)
//
// (Holtrup, Tuning liquefier dynamics, MSc thesis, University of Twente, 2019, sec. 2.2.2 and
// 5.2.3.) This program makes a rheometer-like curve itself (30 shear rates from 0.1 to 10^4 1/s
// at 230 degC, 3 % noise); to fit measured data, fill RheologyData from your file instead
// (SI units: 1/s, Pa.s, K).
//
//   viscosity_fit

#include <cmath>
#include <cstdio>
#include <exception>
#include <random>

#include "tunekit/fitting/rheology_fit.hpp"
#include "tunekit/fitting/viscosity.hpp"

namespace fit = tunekit::fitting;

// Prints each fitted parameter with its 95 % interval.
static void print_fit(const fit::FitResult& r) {
  std::printf("%s: r2 %.4f, AIC %.1f\n", r.model.c_str(), r.diagnostics.r2, r.diagnostics.aic);
  for (const fit::Param& p : r.params) {
    if (p.fixed) continue;  // e.g. the reference temperature, held, not estimated
    std::printf("  %-12s %10.4g %-8s (95 %% interval %.4g to %.4g)\n", p.name.c_str(), p.value, p.unit.c_str(),
                p.ci95_lo, p.ci95_hi);
  }
}

int main() {
  // 1. The data: one temperature, viscosity against shear rate, multiplicative noise.
  const double T_K = fit::celsius_to_kelvin(230.0);
  const double eta0 = 2000.0, tau_star = 40e3, n = 0.38;  // the "unknown" truth (Pa.s, Pa, 1)
  fit::RheologyData all, nozzle;
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.03);
  for (int i = 0; i < 30; ++i) {
    const double gamma = std::pow(10.0, -1.0 + 5.0 * i / 29.0);  // 1/s, log-spaced
    const double eta = fit::cross_viscosity(eta0, tau_star, n, gamma) * std::exp(noise(rng));
    for (fit::RheologyData* d : {&all, &nozzle}) {
      if (d == &nozzle && gamma < 100.0) continue;  // a nozzle shears the melt at 10^2..10^4 1/s
      d->shear_rate_1_s.push_back(gamma);
      d->viscosity_Pa_s.push_back(eta);
      d->temperature_K.push_back(T_K);
    }
  }

  try {
    // 2. Cross over the whole curve. The fit needs no start values: a bounded global search
    //    finds them (NLopt), Ceres polishes, and the intervals come with the result.
    fit::ViscosityFitOptions cross;
    cross.model = fit::ViscosityModel::cross;  // one temperature: no temperature shift
    const fit::FitResult cross_fit = fit::fit_viscosity(all, cross);
    print_fit(cross_fit);

    // 3. A power law over the nozzle's shear rates only (it cannot follow the Newtonian plateau).
    fit::ViscosityFitOptions power;
    power.model = fit::ViscosityModel::power_law;
    const fit::FitResult power_fit = fit::fit_viscosity(nozzle, power);
    print_fit(power_fit);

    // 4. Use the fits: a ViscositySpec evaluates the fitted model anywhere.
    const double gamma = 1000.0;
    std::printf("viscosity at %.0f 1/s: Cross %.1f Pa.s, power law %.1f Pa.s\n", gamma,
                fit::spec_from_fit(cross_fit).viscosity(gamma, T_K),
                fit::spec_from_fit(power_fit).viscosity(gamma, T_K));
  } catch (const std::exception& e) {  // tunekit's InputError / FitError say what is wrong
    std::fprintf(stderr, "viscosity_fit: %s\n", e.what());
    return 1;
  }
  return 0;
}
