#pragma once
// From fitted rheology and nozzle geometry to the liquefier's flow dependence (Holtrup 2019
// sec. 4.5.1 and 5.2.3): the steady pressure drop dP(Q), the incremental flow resistance
// R(Q) = d(dP)/dQ at each operating flow, and the relative time constant.
//
// Model: the liquefier behaves as a compliance C (filament column, melt compressibility;
// independent of flow) discharging through the nozzle's resistance, so its time constant is
// tau(Q) = C R(Q) and the pressure-advance gain that cancels it scales the same way.
// relative_tau(Q) = R(Q) / R(Q_ref) is therefore the factor by which tau and pressure advance
// measured at Q_ref change at Q. A shear-thinning melt (n < 1) has R ~ n dP / Q ~ Q^(n-1):
// tau and pressure advance fall as the flow rises.

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tunekit/fitting/nozzle_pressure.hpp"
#include "tunekit/fitting/viscosity.hpp"

namespace tunekit::ident {

struct LiquefierPredictionOptions {
  fitting::NozzleGeometry geometry;
  fitting::PressureModel model = fitting::PressureModel::boles;
  double temperature_K = 0;
  std::vector<double> flows_mm3_s{0.5, 1, 1.5, 2, 3, 4, 5, 6, 8, 10, 12, 15, 20};
  double reference_flow_mm3_s = 3.0;  ///< Holtrup's (2019) "average conditions"
};

struct LiquefierPrediction {
  double temperature_K = 0;
  double reference_flow_mm3_s = 0;
  std::string pressure_model;
  std::vector<double> flow_mm3_s;
  std::vector<double> pressure_drop_Pa;
  std::vector<double> dP_dQ_Pa_s_per_mm3;
  std::vector<double> relative_tau;         ///< 1 at the reference flow
  std::vector<double> wall_shear_rate_1_s;  ///< with the Rabinowitsch correction
  std::vector<double> flow_index_n;         ///< local power-law index at the wall
};

/// InputError for a non-positive flow or temperature or an invalid geometry.
LiquefierPrediction predict_liquefier(const fitting::ViscositySpec& rheology, const LiquefierPredictionOptions& o);

/// The `results.prediction` object: temperature_K, flow_mm3_s, dP_dQ_Pa_s_per_mm3,
/// relative_tau, reference_flow_mm3_s, plus pressure_drop_Pa, wall_shear_rate_1_s, flow_index_n,
/// pressure_model and a one-line note on the assumption.
nlohmann::json to_json(const LiquefierPrediction& p);

}  // namespace tunekit::ident
