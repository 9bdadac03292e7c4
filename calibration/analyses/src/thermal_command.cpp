// tunekit thermal: the hot end's thermal model from a thermal record (thermal_command.hpp).
#include "tunekit/calibration/analyses/thermal_command.hpp"

#include <cmath>
#include <filesystem>
#include <initializer_list>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/core/file_bytes.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/formats/heater_log.hpp"
#include "tunekit/ident/heater_log_record.hpp"

namespace tunekit::calibration {
namespace {

const formats::CsvColumn* thermal_column(const formats::CsvTable& t, std::initializer_list<const char*> names) {
  for (const char* n : names)
    if (t.has_column(n)) return &t.column(n);
  return nullptr;
}

/// The held-out part's start from the heater-identify run that wrote the record, if any.
double held_out_from_run(const std::string& record_path) {
  const auto run_json = std::filesystem::path(record_path).parent_path() / "run.json";
  std::error_code ec;
  if (!std::filesystem::is_regular_file(run_json, ec)) return fitting::kNaN;
  const auto j = nlohmann::json::parse(read_file_bytes(run_json.string()), nullptr, false);
  if (j.is_discarded() || !j.is_object()) return fitting::kNaN;
  const auto& e = j.value("experiment", nlohmann::json::object());
  if (!e.is_object() || e.value("protocol", "") != "heater-identify") return fitting::kNaN;
  const auto& x = e.value("excitation", nlohmann::json::object());
  return x.is_object() && x.contains("held_out_from_s") && x["held_out_from_s"].is_number()
             ? x["held_out_from_s"].get<double>()
             : fitting::kNaN;
}

nlohmann::json model_json(const ident::ThermalModel& m) {
  return {{"heater_power_w", m.heater_power_w},
          {"block_heat_capacity_j_per_k", m.block_heat_capacity_j_per_k},
          {"sensor_responsiveness_per_s", m.sensor_responsiveness_per_s},
          {"ambient_transfer_w_per_k", m.ambient_transfer_w_per_k},
          {"fan_transfer_w_per_k", m.fan_transfer_w_per_k},
          {"filament_heat_capacity_j_per_k_mm", m.filament_heat_capacity_j_per_k_mm},
          {"ambient_c", m.ambient_c}};
}

/// The record cut to its first `until_s` seconds (NaN: unchanged). InputError when nothing is left.
void keep_first_seconds(ident::ThermalRecord& r, double until_s) {
  if (std::isnan(until_s)) return;
  std::size_t n = 0;
  while (n < r.t_s.size() && r.t_s[n] - r.t_s.front() <= until_s) ++n;
  if (n < 2) throw InputError(fmt::format("--until {:g} s leaves fewer than two samples of the record", until_s));
  for (auto* v : {&r.t_s, &r.temp_c, &r.heater_duty, &r.fan_duty, &r.feed_mm_s, &r.target_c})
    if (v->size() > n) v->resize(n);
}

}  // namespace

bool looks_like_klippy_log(std::string_view bytes) {
  return bytes.rfind("Stats ", 0) == 0 || bytes.find("\nStats ") != std::string_view::npos;
}

ident::ThermalRecord read_klippy_thermal_record(std::string_view bytes, const std::string& heater) {
  const auto log = formats::read_klippy_heater_log(bytes, heater);
  return ident::thermal_record_from_heater_log(log, ident::heated_run(log));
}

ident::ThermalRecord read_thermal_csv(const std::string& path, std::string_view bytes) {
  formats::CsvOptions co;
  co.find_time_column = true;
  const auto t = formats::parse_csv(bytes, path, co);
  const auto hdr = source_location(path, t.header_line);
  const auto* temp = thermal_column(t, {"temperature", "temp"});
  const auto* duty = thermal_column(t, {"heater_duty", "pwm", "duty"});
  if (!temp || !duty)
    throw InputError("a thermal record needs a 'temperature' (degC) and a 'heater_duty' (0..1) column", hdr);
  ident::ThermalRecord r;
  r.t_s = t.column(t.time_column).values;
  r.temp_c = temp->values;
  r.heater_duty = duty->values;
  if (const auto* c = thermal_column(t, {"fan_duty", "fan"})) r.fan_duty = c->values;
  if (const auto* c = thermal_column(t, {"feed"})) r.feed_mm_s = c->values;
  if (const auto* c = thermal_column(t, {"target"})) r.target_c = c->values;
  try {
    ident::check_thermal_record(r);
  } catch (const InputError& e) {
    throw InputError(e.message(), hdr);
  }
  return r;
}

ThermalOutcome compute_thermal(const ThermalOptions& o) {
  ThermalOutcome out;
  out.options = o;
  const std::string bytes = read_file_bytes(o.file);
  out.input = input_digest(o.file, bytes);
  out.format = looks_like_klippy_log(bytes) ? "klippy.log" : "csv";
  out.record = out.format == "csv" ? read_thermal_csv(o.file, bytes) : read_klippy_thermal_record(bytes, o.heater);
  keep_first_seconds(out.record, o.until_s);
  ident::ThermalFitOptions fo = o.fit;
  out.held_out_source = "option";
  if (std::isnan(fo.held_out_from_s)) {
    fo.held_out_from_s = held_out_from_run(o.file);
    out.held_out_source = std::isnan(fo.held_out_from_s) ? "none" : "run.json";
  }
  out.options.fit = fo;
  out.fit = ident::fit_thermal_record(out.record, fo);
  return out;
}

Envelope to_envelope(const ThermalOutcome& o) {
  const auto& f = o.fit;
  Envelope env("thermal");
  env.set_options(
      {{"heater_power_w", o.options.fit.heater_power_w},
       {"held_out_from_s", std::isnan(o.options.fit.held_out_from_s) ? nlohmann::json(nullptr)
                                                                     : nlohmann::json(o.options.fit.held_out_from_s)},
       {"held_out_source", o.held_out_source},
       {"format", o.format},
       {"heater", o.options.heater},
       {"until_s", std::isnan(o.options.until_s) ? nlohmann::json(nullptr) : nlohmann::json(o.options.until_s)}});
  add_input(env, o.input);
  auto& res = env.results();
  res = fitting::to_json(f.fit);
  res["thermal_model"] = model_json(f.model);
  res["variance_factor"] = f.variance_factor;
  res["fitted_samples"] = f.fitted_samples;
  nlohmann::json corr = nlohmann::json::array();
  for (const auto& c : f.correlations) corr.push_back({{"a", c.a}, {"b", c.b}, {"r", c.r}});
  res["strong_correlations"] = corr;
  res["correlation"] = fitting::correlation_json(f.fit);
  if (f.held_out_samples > 0) {
    nlohmann::json steps = nlohmann::json::array();
    for (const auto& s : f.held_out_steps)
      steps.push_back({{"input", s.input},
                       {"from_s", s.from_s},
                       {"to_s", s.to_s},
                       {"before", s.before},
                       {"after", s.after},
                       {"rms_c", s.rms_c},
                       {"samples", s.samples}});
    res["held_out"] = {{"rms_c", f.held_out_rms_c}, {"samples", f.held_out_samples}, {"steps", steps}};
  }
  for (const auto& w : f.warnings) env.warn(w);
  return env;
}

void print_text(const ThermalOutcome& o, std::ostream& os) {
  const auto& f = o.fit;
  os << fmt::format("{}: {} samples, {} fitted; the hot end's thermal model (P = {:g} W given)\n", o.options.file,
                    o.record.t_s.size(), f.fitted_samples, o.options.fit.heater_power_w);
  for (const auto& q : f.fit.params) {
    if (q.fixed) continue;
    os << fmt::format("  {:<34} {:>10.5g} {:<7} 95% [{:.5g}, {:.5g}]\n", q.name, q.value, q.unit, q.ci95_lo, q.ci95_hi);
  }
  const auto& d = f.fit.diagnostics;
  os << fmt::format("  residuals: rms {:.3f} degC, whiteness p {:.3g}, intervals widened by sqrt({:.2f})\n", d.rms,
                    d.whiteness_p, f.variance_factor);
  for (const auto& c : f.correlations) os << fmt::format("  correlated: {} and {} (r = {:+.2f})\n", c.a, c.b, c.r);
  if (f.held_out_samples > 0) {
    os << fmt::format("  held out ({} samples): predicted within {:.3f} degC RMS\n", f.held_out_samples,
                      f.held_out_rms_c);
    for (const auto& s : f.held_out_steps)
      os << fmt::format("    {} step {:g} -> {:g} at {:.0f} s: {:.3f} degC RMS\n", s.input, s.before, s.after, s.from_s,
                        s.rms_c);
  }
}

}  // namespace tunekit::calibration
