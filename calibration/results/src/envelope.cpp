#include "tunekit/calibration/results/envelope.hpp"

#include <filesystem>
#include <fstream>
#include <ostream>

#include <fmt/format.h>

#include "tunekit/calibration/results/history_record.hpp"
#include "tunekit/calibration/results/requirements.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/core/version.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/core/atomic_file.hpp"
#include "tunekit/core/file_bytes.hpp"

namespace tunekit::calibration {

std::string sha256_file(const std::string& path) { return sha256_hex(read_file_bytes(path)); }

Envelope::Envelope(std::string command) : command_(std::move(command)) {}

void Envelope::add_input(const std::string& path) { add_input(path, read_file_bytes(path)); }

void Envelope::add_input(const std::string& path, std::string_view bytes) {
  add_input_digest(path, sha256_hex(bytes), bytes.size());
}

std::vector<std::string> Envelope::input_paths() const {
  std::vector<std::string> out;
  for (const auto& i : inputs_) out.push_back(i.value("path", std::string()));
  return out;
}

void Envelope::add_input_digest(const std::string& path, std::string sha256, std::size_t size_bytes) {
  inputs_.push_back({{"path", path}, {"sha256", std::move(sha256)}, {"bytes", size_bytes}});
}

nlohmann::json Envelope::to_json() const {
  return {{"schema_version", kSchemaVersion},
          {"tool", {{"name", "tunekit"}, {"version", core::kVersion}}},
          {"command", command_},
          {"options", options_},
          {"inputs", inputs_},
          {"results", results_},
          {"diagnostics", diagnostics_},
          {"warnings", warnings_}};
}

std::string Envelope::dump() const { return to_json().dump(2) + "\n"; }

std::string utf8_or_latin1(std::string_view s) {
  std::string out;
  out.reserve(s.size());
  std::size_t i = 0;
  auto cont = [&](std::size_t k) { return k < s.size() && (static_cast<unsigned char>(s[k]) & 0xC0) == 0x80; };
  while (i < s.size()) {
    const auto c = static_cast<unsigned char>(s[i]);
    std::size_t len = 0;
    if (c < 0x80) len = 1;
    else if (c >= 0xC2 && c <= 0xDF && cont(i + 1)) len = 2;
    else if (c >= 0xE0 && c <= 0xEF && cont(i + 1) && cont(i + 2)) {
      const auto c1 = static_cast<unsigned char>(s[i + 1]);
      if (!(c == 0xE0 && c1 < 0xA0) && !(c == 0xED && c1 >= 0xA0)) len = 3;  // no overlong forms or surrogates
    } else if (c >= 0xF0 && c <= 0xF4 && cont(i + 1) && cont(i + 2) && cont(i + 3)) {
      const auto c1 = static_cast<unsigned char>(s[i + 1]);
      if (!(c == 0xF0 && c1 < 0x90) && !(c == 0xF4 && c1 >= 0x90)) len = 4;
    }
    if (len) {
      out.append(s.substr(i, len));
      i += len;
    } else {
      out.push_back(static_cast<char>(0xC0 | (c >> 6)));
      out.push_back(static_cast<char>(0x80 | (c & 0x3F)));
      ++i;
    }
  }
  return out;
}

namespace {

/// Every string and key of `j` as valid UTF-8 (see utf8_or_latin1).
void make_utf8(nlohmann::json& j) {
  if (j.is_string()) {
    auto& s = j.get_ref<std::string&>();
    s = utf8_or_latin1(s);
  } else if (j.is_array()) {
    for (auto& x : j) make_utf8(x);
  } else if (j.is_object()) {
    nlohmann::json fixed = nlohmann::json::object();
    for (auto& [k, v] : j.items()) {
      make_utf8(v);
      fixed[utf8_or_latin1(k)] = std::move(v);
    }
    j = std::move(fixed);
  }
}

}  // namespace

Emission prepare_emission(const Envelope& env, const OutputOptions& o) {
  // Requirements are checked before anything is written so that the JSON records them.
  std::vector<RequirementOutcome> outcomes;
  for (const auto& expr : o.require) outcomes.push_back(evaluate_requirement(parse_requirement(expr), env.results()));
  nlohmann::json j = env.to_json();
  if (!outcomes.empty()) {
    nlohmann::json reqs = nlohmann::json::array();
    for (const auto& r : outcomes)
      reqs.push_back(
          {{"expression", r.requirement.expression}, {"path", r.resolved_path}, {"value", r.value}, {"met", r.met}});
    j["requirements"] = reqs;
  }
  make_utf8(j);
  Emission e;
  e.text = j.dump(2) + "\n";
  e.document = std::move(j);
  for (const auto& r : outcomes) {
    if (r.met) continue;
    e.unmet.push_back(fmt::format("tunekit: requirement not met: {} ({} = {:.6g})\n", r.requirement.expression,
                                  r.resolved_path, r.value));
    e.exit_code = static_cast<int>(ExitCode::fit_failed);
  }
  return e;
}

bool is_special_output(const std::string& path) {
  std::error_code ec;
  const auto st = std::filesystem::status(path, ec);
  return !ec && std::filesystem::exists(st) && !std::filesystem::is_regular_file(st) &&
         !std::filesystem::is_directory(st);
}

void write_output_text(const std::string& path, const std::string& text) {
  if (!is_special_output(path)) {
    core::write_file_atomic(path, text);
    return;
  }
  // A device or pipe (-o /dev/stdout): written in place, never replaced.
  std::ofstream f(path, std::ios::binary);
  if (!f) throw InputError("cannot write the results file", path);
  f << text;
  if (!f.flush()) throw InputError("cannot write the results file", path);
}

void check_output_not_input(const std::string& path, const std::string& option,
                            const std::vector<std::string>& inputs) {
  if (path.empty() || is_special_output(path)) return;
  for (const auto& in : inputs)
    if (!in.empty() && same_file(path, in))
      throw InputError(
          fmt::format("{} {} is the input file {}: writing it would replace the input; choose another "
                      "output file",
                      option, path, in));
}

int finish_emission(const Envelope& env, const OutputOptions& o, const Emission& e, CliContext& ctx,
                    bool write_output_file) {
  if (write_output_file) check_output_not_input(o.output_path, "--json-file", env.input_paths());
  if (write_output_file && !o.output_path.empty()) write_output_text(o.output_path, e.text);
  if (o.record) record_result(e.document, o, ctx);
  if (o.json) ctx.out << e.text;
  for (const auto& w : env.warnings()) ctx.err << "tunekit: warning: " << utf8_or_latin1(w) << "\n";
  for (const auto& u : e.unmet) ctx.err << u;
  return e.exit_code;
}

int emit(const Envelope& env, const OutputOptions& o, CliContext& ctx) {
  return finish_emission(env, o, prepare_emission(env, o), ctx);
}

}  // namespace tunekit::calibration
