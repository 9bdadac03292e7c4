// The whole-record liquefier model as tunekit step and tunekit freq report it (whole_record.hpp).
#include "tunekit/calibration/analyses/whole_record.hpp"

#include <cmath>
#include <filesystem>
#include <string_view>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/fitting/liquefier_model.hpp"
#include "tunekit/calibration/presentation/report.hpp"
#include "tunekit/fitting/stats.hpp"

namespace tunekit::calibration {

std::string feed_track_for(const std::string& given, const std::string& log) {
  if (!given.empty()) return given;
  const auto beside = std::filesystem::path(log).parent_path() / "feed_track.csv";
  std::error_code ec;
  return std::filesystem::is_regular_file(beside, ec) ? beside.string() : std::string();
}

std::optional<ident::FeedTrackAlignment> aligned_feed_track(const InputFile* track, std::span<const double> t,
                                                            std::span<const double> u) {
  if (track == nullptr) return std::nullopt;
  return ident::align_feed_track(ident::parse_feed_track_csv(track->bytes(), track->path()), t, u);
}

void print_whole_record(std::ostream& os, const WholeRecordResult& r, double u_compare) {
  if (!r.model) {
    if (!r.error.empty()) os << "  whole record: not fitted: " << r.error << "\n";
    return;
  }
  const auto& m = *r.model;
  const auto& f = m.model.fit;
  const auto& a = f.derived.front();
  const auto& b = f.param("b");
  const auto& th = f.param("theta_s");
  os << fmt::format("  whole record: tau = a u^b, a = {} {}, b = {}, theta = {} s {}; {} sensor",
                    display_number(a.value), display_interval(a.ci95_lo, a.ci95_hi),
                    b.fixed ? std::string("0 (linear: b's interval holds 0)")
                            : display_number(b.value) + " " + display_interval(b.ci95_lo, b.ci95_hi),
                    display_number(th.value), display_interval(th.ci95_lo, th.ci95_hi),
                    fitting::to_string(m.model.sensor));
  if (!m.checks.empty())
    os << fmt::format("; {} of {} step fits disagree with it", ident::disagreeing_checks(m.checks), m.checks.size());
  os << "\n";
  // The model's tau where its interval is narrowest: the number calibrate's summary lists.
  const auto& ref = f.param("tau_ref_s");
  os << fmt::format("    its tau at its reference input u = {:.4g} {}: {} s {}\n", m.model.reference_input,
                    m.input_unit, display_number(ref.value), display_interval(ref.ci95_lo, ref.ci95_hi));
  if (std::isfinite(u_compare) && u_compare > 0) {
    // Two-sided 95 % quantile of the normal distribution.
    const double tau = m.tau_at(u_compare), se = m.tau_stderr_at(u_compare);
    os << fmt::format("    its tau at the record's mean input u = {:.4g} {}: {} s {}\n", u_compare, m.input_unit,
                      display_number(tau), display_interval(tau - fitting::kZ95 * se, tau + fitting::kZ95 * se));
  }
  // The melt below the data, measured: what the advance's design starts from (docs/export.md).
  if (const auto& v = m.rest_volume) {
    // The input unit times s: a feed's mm/s gives mm of filament, a flow's mm^3/s mm^3.
    const std::string& in = m.input_unit;
    const bool per_s = in.size() > 2 && in.compare(in.size() - 2, 2, "/s") == 0;
    const std::string volume = per_s ? in.substr(0, in.size() - 2) : in + ".s";
    os << fmt::format("    stored at its first level u = {:.4g} {} (from the start-up transient): {} {} {}\n", v->input,
                      in, display_number(v->value), volume, display_interval(v->ci95_lo, v->ci95_hi));
  }
}

void add_whole_record(Envelope& env, const WholeRecordResult& r) {
  if (r.model) {
    env.results()["whole_record"] = ident::to_json(*r.model);
    for (const auto& w : r.model->warnings) env.warn(w);
  } else if (!r.error.empty()) {
    env.results()["whole_record"] = {{"error", r.error}};
  }
}

}  // namespace tunekit::calibration
