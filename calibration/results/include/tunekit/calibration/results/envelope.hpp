#pragma once
// The JSON envelope every command writes: schema version, tool version, command, options,
// inputs (path and SHA-256 of the bytes read), results with units, diagnostics and warnings.
// Keys are sorted and nothing time- or host-dependent is included, so the same inputs and
// options give byte-identical output.

#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "tunekit/calibration/results/context.hpp"

namespace tunekit::calibration {

inline constexpr int kSchemaVersion = 1;

/// Lower-case hex SHA-256 of a byte string.
std::string sha256_hex(std::string_view bytes);
/// SHA-256 of a file's bytes; InputError if it cannot be read.
std::string sha256_file(const std::string& path);

class Envelope {
 public:
  explicit Envelope(std::string command);

  void set_options(nlohmann::json options) { options_ = std::move(options); }
  /// Records an input file by path, hashing its bytes.
  void add_input(const std::string& path);
  /// Records an input whose bytes are already in memory.
  void add_input(const std::string& path, std::string_view bytes);
  /// The same with the digest already computed (e.g. on another thread while the data are parsed).
  void add_input_digest(const std::string& path, std::string sha256, std::size_t size_bytes);
  void warn(std::string message) { warnings_.push_back(std::move(message)); }

  nlohmann::json& results() { return results_; }
  nlohmann::json& diagnostics() { return diagnostics_; }
  const nlohmann::json& results() const { return results_; }
  const std::vector<std::string>& warnings() const { return warnings_; }
  /// The paths of the inputs recorded so far.
  std::vector<std::string> input_paths() const;

  nlohmann::json to_json() const;
  /// Pretty-printed with two-space indent and a final newline.
  std::string dump() const;

 private:
  std::string command_;
  nlohmann::json options_ = nlohmann::json::object();
  nlohmann::json inputs_ = nlohmann::json::array();
  nlohmann::json results_ = nlohmann::json::object();
  nlohmann::json diagnostics_ = nlohmann::json::object();
  std::vector<std::string> warnings_;
};

/// Writes the envelope where OutputOptions say (stdout with --json, a file with --output),
/// prints warnings on stderr (one line each), and returns the process exit code
/// (0, or 1 when a --require threshold is not met).
/// The JSON file is replaced atomically. Strings that are not valid UTF-8 (a Latin-1 comment in
/// a configuration file, a file name) are carried over byte for byte as the Latin-1 code points
/// U+0080..U+00FF instead of failing.
int emit(const Envelope& env, const OutputOptions& o, CliContext& ctx);

/// emit() in two steps, for commands that write other files together with the JSON file
/// (all or nothing): prepare_emission() evaluates the --require thresholds and renders the
/// JSON text; finish_emission() prints it and the warnings and returns the exit code, writing
/// the --output file only when `write_output_file` (the caller has written it otherwise).
struct Emission {
  nlohmann::json document;  ///< the JSON document (what --record stores)
  std::string text;         ///< the same, as text ending in a newline
  int exit_code = 0;
  std::vector<std::string> unmet;  ///< "tunekit: requirement not met: ..." lines
};
Emission prepare_emission(const Envelope& env, const OutputOptions& o);
int finish_emission(const Envelope& env, const OutputOptions& o, const Emission& e, CliContext& ctx,
                    bool write_output_file = true);

/// True for an existing path that is neither a regular file nor a directory (a device such as
/// /dev/stdout, a pipe): results are written into it in place instead of replacing it.
bool is_special_output(const std::string& path);

/// Refuses (InputError, exit 2) an output `path`, given with `option`, that is the same file as
/// one of `inputs` (core::same_file): writing it would replace an input. Devices are exempt.
void check_output_not_input(const std::string& path, const std::string& option, const std::vector<std::string>& inputs);
/// Writes a results file: atomically replaced when it is (or will be) a regular file, written
/// in place when it is a device or pipe.
void write_output_text(const std::string& path, const std::string& text);

/// `bytes` as valid UTF-8: valid sequences are kept, every other byte becomes the UTF-8
/// encoding of the Latin-1 code point of the same value.
std::string utf8_or_latin1(std::string_view bytes);

/// A column's unit as results report it: "1" (dimensionless) when the CSV header names none.
inline std::string unit_or_1(const std::string& unit) { return unit.empty() ? "1" : unit; }

}  // namespace tunekit::calibration
