#include "tunekit/cli/envelope.hpp"

#include <fstream>
#include <ostream>

#include <fmt/format.h>
#include <openssl/evp.h>

#include "tunekit/cli/history_record.hpp"
#include "tunekit/cli/requirements.hpp"
#include "tunekit/fitting/error.hpp"
#include "tunekit/ident/csv.hpp"

#ifndef TUNEKIT_VERSION
#define TUNEKIT_VERSION "0.0.0"
#endif

namespace tunekit::cli {

std::string sha256_hex(std::string_view bytes) {
  unsigned char md[EVP_MAX_MD_SIZE];
  unsigned int len = 0;
  EVP_Digest(bytes.data(), bytes.size(), md, &len, EVP_sha256(), nullptr);
  std::string hex;
  hex.reserve(len * 2);
  for (unsigned int i = 0; i < len; ++i) hex += fmt::format("{:02x}", md[i]);
  return hex;
}

std::string sha256_file(const std::string& path) { return sha256_hex(ident::read_file_bytes(path)); }

Envelope::Envelope(std::string command) : command_(std::move(command)) {}

void Envelope::add_input(const std::string& path) { add_input(path, ident::read_file_bytes(path)); }

void Envelope::add_input(const std::string& path, std::string_view bytes) {
  add_input_digest(path, sha256_hex(bytes), bytes.size());
}

void Envelope::add_input_digest(const std::string& path, std::string sha256, std::size_t size_bytes) {
  inputs_.push_back({{"path", path}, {"sha256", std::move(sha256)}, {"bytes", size_bytes}});
}

nlohmann::json Envelope::to_json() const {
  return {{"schema_version", kSchemaVersion},
          {"tool", {{"name", "tunekit"}, {"version", TUNEKIT_VERSION}}},
          {"command", command_},
          {"options", options_},
          {"inputs", inputs_},
          {"results", results_},
          {"diagnostics", diagnostics_},
          {"warnings", warnings_}};
}

std::string Envelope::dump() const { return to_json().dump(2) + "\n"; }

int emit(const Envelope& env, const OutputOptions& o, CliContext& ctx) {
  // Requirements are checked before anything is written so that the JSON records them.
  std::vector<RequirementOutcome> outcomes;
  for (const auto& expr : o.require) outcomes.push_back(evaluate_requirement(parse_requirement(expr), env.results()));
  nlohmann::json j = env.to_json();
  if (!outcomes.empty()) {
    nlohmann::json reqs = nlohmann::json::array();
    for (const auto& r : outcomes)
      reqs.push_back({{"expression", r.requirement.expression}, {"path", r.resolved_path}, {"value", r.value}, {"met", r.met}});
    j["requirements"] = reqs;
  }
  const std::string text = j.dump(2) + "\n";
  if (o.json) ctx.out << text;
  if (!o.output_path.empty()) {
    std::ofstream f(o.output_path, std::ios::binary);
    if (!f) throw InputError("cannot write the results file", o.output_path);
    f << text;
    if (!f.flush()) throw InputError("cannot write the results file", o.output_path);
  }
  if (o.record) record_result(j, o, ctx);
  for (const auto& w : env.warnings()) ctx.err << "tunekit: warning: " << w << "\n";
  int code = 0;
  for (const auto& r : outcomes) {
    if (r.met) continue;
    ctx.err << fmt::format("tunekit: requirement not met: {} ({} = {:.6g})\n", r.requirement.expression, r.resolved_path,
                           r.value);
    code = static_cast<int>(ExitCode::fit_failed);
  }
  return code;
}

}  // namespace tunekit::cli
