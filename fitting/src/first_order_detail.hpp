#pragma once
// What the single-step fit (first_order.cpp) and the pooled fit (first_order_pooled.cpp) of
// first-order step responses share: the record checks, the model with its derivatives at one
// sample, the residuals, and the identifiability check. Private to the fitting library.

#include <array>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "tunekit/fitting/first_order.hpp"

namespace tunekit::fitting::first_order_detail {

constexpr double kTauMaxFactor = 100.0;  // tau may be at most this many record lengths

/// InputError unless the record has increasing, finite times and finite outputs.
void check_record(const StepRecord& r, const std::string& what);
/// Mean of v[b, e).
double mean_of(const std::vector<double>& v, std::size_t b, std::size_t e);

/// The model y0 + K du (1 - exp(-(t - t_step - theta)/tau)) at sample i and its derivatives.
struct StepModelPoint {
  double m, dK, dtau, dtheta;
};
StepModelPoint step_model_at(const StepRecord& r, std::size_t i, double K, double tau, double theta, double y0);

/// logged_input_is_ideal_step (first_order.hpp).
bool input_is_ideal_step(const StepRecord& r);

/// The response to a record's commanded input track (StepRecord::input_t, input_u) and its
/// derivatives at every sample (first_order_track.cpp).
void track_model_points(const StepRecord& r, double K, double tau, double theta, double y0,
                        std::vector<StepModelPoint>& out);

/// The model and its derivatives at every sample of a record: step_model_at for an ideal step,
/// the response to the commanded input track (StepRecord::input_t) when the record has one, else
/// to the recorded input (StepRecord::u) when it has that.
void step_model_points(const StepRecord& r, double K, double tau, double theta, double y0,
                       std::vector<StepModelPoint>& out);

/// Residuals (model - data) of every sample into res, and, when jac is not null, the Jacobian
/// row-major with `width` columns, K, tau, theta and y0 in columns cols[0..3].
void step_residuals(const StepRecord& r, double K, double tau, double theta, double y0, double* res, double* jac,
                    std::size_t width, const std::size_t cols[4]);

/// The Gauss-Newton normal equations J'J and J'r of one step at p = {K, tau_s, theta_s, y0};
/// returns the residual sum of squares. When res_out is not empty (one element per sample), the
/// residuals (model - data) are stored there as well.
double normal_equations(const StepRecord& r, const double p[4], Eigen::Matrix4d& JtJ, Eigen::Vector4d& Jtr,
                        std::span<double> res_out = {});

/// Ljung-Box p below which the residuals count as not white and the intervals take the
/// model error in (a sandwich covariance).
constexpr double kWhitenessRobustP = 0.01;

/// The standard uncertainty of a step's instant from the sampling: dt / sqrt(12), dt the
/// record's median sample interval (the instant lies somewhere within a sample). `scratch`, when
/// it has at least one element per sample, holds the intervals (it is overwritten); otherwise a
/// buffer is allocated.
double step_instant_resolution(const StepRecord& r, std::span<double> scratch = {});

/// FitError when tau_s ran to its bound or is not determined, or theta_s ran to its bound.
void check_identifiable(const FitResult& f, const StepRecord* rec, double duration, bool have_stderr);
/// Time from the step to the last sample (s).
double response_duration(const StepRecord& r);

}  // namespace tunekit::fitting::first_order_detail
