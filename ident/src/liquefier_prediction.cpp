#include "tunekit/ident/liquefier_prediction.hpp"

#include <cmath>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"

namespace tunekit::ident {

LiquefierPrediction predict_liquefier(const fitting::ViscositySpec& v, const LiquefierPredictionOptions& o) {
  fitting::validate(o.geometry);
  if (!(o.temperature_K > 0)) throw InputError("liquefier prediction: the temperature must be positive (K)");
  if (!(o.reference_flow_mm3_s > 0))
    throw InputError(fmt::format("liquefier prediction: the reference flow must be positive (is {:g} mm3/s)",
                                 o.reference_flow_mm3_s));
  if (o.flows_mm3_s.empty()) throw InputError("liquefier prediction: no flows given");
  LiquefierPrediction p;
  p.temperature_K = o.temperature_K;
  p.reference_flow_mm3_s = o.reference_flow_mm3_s;
  p.pressure_model = fitting::to_string(o.model);
  const double r_ref =
      fitting::pressure_drop_slope(o.model, v, o.reference_flow_mm3_s * 1e-9, o.temperature_K, o.geometry) * 1e-9;
  if (!(r_ref > 0) || !std::isfinite(r_ref))
    throw FitError("liquefier prediction: the flow resistance at the reference flow is not positive");
  for (double q : o.flows_mm3_s) {
    if (!(q > 0)) throw InputError(fmt::format("liquefier prediction: flows must be positive (got {:g} mm3/s)", q));
    const double Q = q * 1e-9;
    const auto lp = fitting::local_power_law(v, Q, o.geometry.d_m, o.temperature_K);
    const double r = fitting::pressure_drop_slope(o.model, v, Q, o.temperature_K, o.geometry) * 1e-9;
    p.flow_mm3_s.push_back(q);
    p.pressure_drop_Pa.push_back(fitting::pressure_drop(o.model, v, Q, o.temperature_K, o.geometry));
    p.dP_dQ_Pa_s_per_mm3.push_back(r);
    p.relative_tau.push_back(r / r_ref);
    p.wall_shear_rate_1_s.push_back(lp.wall_shear_rate_1_s);
    p.flow_index_n.push_back(lp.n);
  }
  return p;
}

nlohmann::json to_json(const LiquefierPrediction& p) {
  return {{"temperature_K", p.temperature_K},
          {"reference_flow_mm3_s", p.reference_flow_mm3_s},
          {"pressure_model", p.pressure_model},
          {"flow_mm3_s", p.flow_mm3_s},
          {"pressure_drop_Pa", p.pressure_drop_Pa},
          {"dP_dQ_Pa_s_per_mm3", p.dP_dQ_Pa_s_per_mm3},
          {"relative_tau", p.relative_tau},
          {"wall_shear_rate_1_s", p.wall_shear_rate_1_s},
          {"flow_index_n", p.flow_index_n},
          {"note",
           "tau(Q) = C dP/dQ with a flow-independent compliance C; relative_tau = "
           "(dP/dQ)(Q) / (dP/dQ)(reference_flow) also scales pressure advance"}};
}

}  // namespace tunekit::ident
