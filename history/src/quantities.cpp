#include "tunekit/history/quantities.hpp"

#include <cmath>
#include <set>

namespace tunekit::history {
namespace {

const nlohmann::json* qty_at(const nlohmann::json& root, std::initializer_list<std::string> keys) {
  const nlohmann::json* cur = &root;
  for (const auto& k : keys) {
    if (!cur->is_object() || !cur->contains(k)) return nullptr;
    cur = &(*cur)[k];
  }
  return cur;
}

double qty_number(const nlohmann::json* j) {
  if (j == nullptr) return std::nan("");
  if (j->is_number()) return j->get<double>();
  if (j->is_object() && j->contains("value") && (*j)["value"].is_number()) return (*j)["value"].get<double>();
  return std::nan("");
}

class QuantityList {
 public:
  // A {value, stderr} object or a bare number.
  void param(const std::string& name, const nlohmann::json* p, const std::string& unit) {
    if (p == nullptr || seen_.count(name)) return;
    Quantity q{name, qty_number(p), std::nan(""), "", unit};
    if (!std::isfinite(q.value)) return;
    if (p->is_object() && p->contains("stderr") && (*p)["stderr"].is_number())
      q.stderr_value = (*p)["stderr"].get<double>();
    if (p->is_object() && p->contains("unit") && (*p)["unit"].is_string() && unit.empty())
      q.unit = (*p)["unit"].get<std::string>();
    add(std::move(q));
  }
  void number(const std::string& name, const nlohmann::json* v, const nlohmann::json* se, const std::string& unit) {
    if (seen_.count(name)) return;
    Quantity q{name, qty_number(v), qty_number(se), "", unit};
    if (std::isfinite(q.value)) add(std::move(q));
  }
  void word(const std::string& name, const nlohmann::json* v) {
    if (v == nullptr || !v->is_string() || v->get<std::string>().empty() || seen_.count(name)) return;
    add({name, std::nan(""), std::nan(""), v->get<std::string>(), "1"});
  }
  std::vector<Quantity> take() { return std::move(list_); }

 private:
  void add(Quantity q) {
    if (q.unit.empty()) q.unit.push_back('1');  // dimensionless (push_back: GCC 12 warns falsely on = "1")
    seen_.insert(q.name);
    list_.push_back(std::move(q));
  }
  std::vector<Quantity> list_;
  std::set<std::string> seen_;
};

// The whole-record model's tau at its reference feed, dead time and (a flow-like sensor's) gain:
// the liquefier's quantities calibrate's summary lists. `prefix` names the record they come from.
void whole_record_quantities(QuantityList& out, const nlohmann::json* step, const std::string& prefix) {
  const auto* wr = step != nullptr ? qty_at(*step, {"whole_record"}) : nullptr;
  if (wr == nullptr || !wr->is_object() || wr->contains("error")) return;
  out.param(prefix + "tau_s", qty_at(*wr, {"tau_ref_s"}), "s");
  out.param(prefix + "theta_s", qty_at(*wr, {"theta_s"}), "s");
  const auto* sensor = qty_at(*wr, {"sensor"});
  const auto* g = qty_at(*wr, {"model", "params", "g"});
  if (sensor != nullptr && *sensor == "flow" && g != nullptr) {
    const auto* unit = qty_at(*g, {"unit"});
    out.param(prefix + "K", g, unit != nullptr && unit->is_string() ? unit->get<std::string>() : std::string("1"));
  }
}

void liquefier_step(QuantityList& out, const nlohmann::json* step) {
  if (step == nullptr) return;
  whole_record_quantities(out, step, "record.");
  const auto* params = qty_at(*step, {"pooled", "params"});
  if (params == nullptr) return;
  std::string gain_unit = "1";
  if (const auto* u = qty_at(*step, {"units", "K"}); u != nullptr && u->is_string()) gain_unit = u->get<std::string>();
  out.param("tau_s", qty_at(*params, {"tau_s"}), "s");
  out.param("theta_s", qty_at(*params, {"theta_s"}), "s");
  out.param("K", qty_at(*params, {"K"}), gain_unit);
}

// The frequency response's parameters from the fit the freq analysis reports (results.fit:
// the output-error fit when there is one), the same ones its report and export show. Results
// written before freq named its fit (imports of older runs) are read by the same rule.
void liquefier_freq(QuantityList& out, const nlohmann::json* freq) {
  if (freq == nullptr) return;
  whole_record_quantities(out, freq, "freq.record.");
  const auto* params = qty_at(*freq, {"fit", "params"});
  if (params == nullptr) params = qty_at(*freq, {"tf_oe_fit", "params"});
  if (params == nullptr) params = qty_at(*freq, {"tf_fit", "params"});
  if (params == nullptr) return;
  out.param("freq.tau_s", qty_at(*params, {"tau_s"}), "s");
  out.param("freq.theta_s", qty_at(*params, {"theta_s"}), "s");
}

void axis_quantities(QuantityList& out, const nlohmann::json* axes_json) {
  if (axes_json == nullptr || !axes_json->is_object()) return;
  for (const auto& [axis, a] : axes_json->items()) {
    if (!a.is_object()) continue;
    const auto* modes = qty_at(a, {"modes"});
    if (modes != nullptr && modes->is_array() && !modes->empty()) {
      std::size_t dom = 0;
      if (const auto* d = qty_at(a, {"fit", "dominant_mode"}); d != nullptr && d->is_number_integer() &&
                                                               d->get<long>() >= 0 &&
                                                               static_cast<std::size_t>(d->get<long>()) < modes->size())
        dom = static_cast<std::size_t>(d->get<long>());
      const auto& m = (*modes)[dom];
      out.number(axis + ".freq_hz", qty_at(m, {"freq_hz"}), qty_at(m, {"freq_stderr_hz"}), "Hz");
      out.number(axis + ".zeta", qty_at(m, {"zeta"}), qty_at(m, {"zeta_stderr"}), "1");
    }
    if (const auto* rec = qty_at(a, {"recommended"}); rec != nullptr) {
      out.word(axis + ".shaper", qty_at(*rec, {"type"}));
      out.number(axis + ".shaper_freq_hz", qty_at(*rec, {"freq_hz"}), nullptr, "Hz");
      out.number(axis + ".max_accel_mm_s2", qty_at(*rec, {"max_accel_mm_s2"}), nullptr, "mm/s^2");
    }
  }
}

void advance_quantities(QuantityList& out, const nlohmann::json* settings) {
  if (settings == nullptr) return;
  out.number("pa_k_s", qty_at(*settings, {"pa_k_s"}), nullptr, "s");
  out.number("pa_smooth_s", qty_at(*settings, {"pa_smooth_s"}), nullptr, "s");
}

// tunekit belts: each belt's fundamental and, when the span was known, its tension.
void belt_quantities(QuantityList& out, const nlohmann::json& r) {
  out.number("belt_a.freq_hz", qty_at(r, {"freq_a_hz"}), qty_at(r, {"a", "freq_stderr_hz"}), "Hz");
  out.number("belt_b.freq_hz", qty_at(r, {"freq_b_hz"}), qty_at(r, {"b", "freq_stderr_hz"}), "Hz");
  out.param("belt_a.tension_n", qty_at(r, {"tension_a_n"}), "N");
  out.param("belt_b.tension_n", qty_at(r, {"tension_b_n"}), "N");
}

// The hot end's thermal model (tunekit thermal; calibrate --thermal): its parameters under
// "hot_end.", so that a failing cartridge (C and A seen against the same given power) or a loose
// thermistor (a slower sensor, R) shows as drift.
void thermal_quantities(QuantityList& out, const nlohmann::json* thermal) {
  const auto* params = thermal != nullptr ? qty_at(*thermal, {"params"}) : nullptr;
  if (params == nullptr) return;
  for (const char* name : {"block_heat_capacity_j_per_k", "sensor_responsiveness_per_s", "ambient_transfer_w_per_k",
                           "fan_transfer_w_per_k", "filament_heat_capacity_j_per_k_mm", "ambient_c"})
    if (const auto* p = qty_at(*params, {name}); p != nullptr && !(p->contains("fixed") && (*p)["fixed"] == true))
      out.param(std::string("hot_end.") + name, p, "");
  out.number("hot_end.held_out_rms_c", qty_at(*thermal, {"held_out", "rms_c"}), nullptr, "degC");
}

// Any other fitted parameter: objects under a "params" key whose members have a value.
void other_params(QuantityList& out, const std::string& command, const nlohmann::json& j, int depth) {
  if (depth > 6 || !j.is_object()) return;
  for (const auto& [k, v] : j.items()) {
    if (k == "params" && v.is_object()) {
      for (const auto& [pname, p] : v.items())
        if (p.is_object() && p.contains("value")) out.param(command + "." + pname, &p, "");
    } else if (v.is_object()) {
      other_params(out, command, v, depth + 1);
    }
  }
}

}  // namespace

std::vector<Quantity> extract_quantities(const std::string& command, const nlohmann::json& results_or_envelope) {
  const nlohmann::json& r = results_or_envelope.contains("results") && results_or_envelope.contains("command")
                                ? results_or_envelope["results"]
                                : results_or_envelope;
  QuantityList out;
  if (command == "calibrate") {
    liquefier_step(out, qty_at(r, {"liquefier", "step"}));
    liquefier_freq(out, qty_at(r, {"liquefier", "freq"}));
    axis_quantities(out, qty_at(r, {"axes"}));
    advance_quantities(out, qty_at(r, {"compensators", "settings"}));
    thermal_quantities(out, qty_at(r, {"thermal"}));
  } else if (command == "thermal") {
    thermal_quantities(out, &r);
  } else if (command == "step") {
    liquefier_step(out, &r);
  } else if (command == "freq") {
    liquefier_freq(out, &r);
  } else if (command == "shaper" || command == "resonance") {
    axis_quantities(out, qty_at(r, {"axes"}));
  } else if (command == "belts") {
    belt_quantities(out, r);
  } else if (command == "export") {
    advance_quantities(out, qty_at(r, {"settings"}));
  } else {
    other_params(out, command, r, 0);
  }
  return out.take();
}

const std::vector<std::string>& headline_quantities() {
  static const std::vector<std::string> names{"tau_s",    "theta_s",   "K",      "x.freq_hz", "x.zeta",
                                              "x.shaper", "y.freq_hz", "y.zeta", "y.shaper",  "pa_k_s"};
  return names;
}

}  // namespace tunekit::history
