// Which format a profile file is in (by its content), the dispatch to the importers, and the
// imported profile written as a TOML machine profile with the source of every value.
#include "tunekit/machine/profile_import.hpp"

#include <filesystem>
#include <sstream>

#include <fmt/format.h>
#include <toml++/toml.h>

#include "tunekit/core/error.hpp"
#include "tunekit/core/file_bytes.hpp"
#include "tunekit/core/input_read_scope.hpp"
#include "tunekit/core/text.hpp"

namespace tunekit::machine {
namespace {

std::string import_trim(std::string_view s) {
  std::size_t b = 0, e = s.size();
  while (b < e && (s[b] == ' ' || s[b] == '\t' || s[b] == '\r')) ++b;
  while (e > b && (s[e - 1] == ' ' || s[e - 1] == '\t' || s[e - 1] == '\r')) --e;
  return std::string(s.substr(b, e - b));
}

bool has_extension(const std::string& path, const char* ext) {
  return core::iequals(std::filesystem::path(path).extension().string(), ext);
}

/// Counts of the kinds of lines that tell the formats apart.
struct ImportLineKinds {
  int nonblank = 0, defines = 0, sections = 0, colon_options = 0, gcode = 0, echo = 0, rrf = 0;
  bool machine_table = false;
  bool printer_section = false;  ///< [printer] or [include ...]: Klipper only
};

/// A G-code line's command word ("M208"), or "" (an "echo:" or "Recv:" prefix is skipped).
std::string detect_gcode_command(std::string t, bool& echo) {
  for (const char* prefix : {"Recv:", "echo:"})
    if (t.rfind(prefix, 0) == 0) {
      t = import_trim(t.substr(std::string(prefix).size()));
      echo = true;
    }
  std::size_t n = 1;
  if (t.empty() || (t[0] != 'M' && t[0] != 'G' && t[0] != 'm' && t[0] != 'g')) return {};
  while (n < t.size() && std::isdigit(static_cast<unsigned char>(t[n]))) ++n;
  if (n == 1 || (n < t.size() && t[n] != ' ' && t[n] != '\t' && t[n] != ';')) return {};
  return core::lower(t.substr(0, n));
}

void classify_line(const std::string& raw, ImportLineKinds& k) {
  const std::string t = import_trim(raw);
  if (t.empty()) return;
  ++k.nonblank;
  if (t.rfind("#define", 0) == 0 || (t[0] == '#' && import_trim(t.substr(1)).rfind("define ", 0) == 0)) ++k.defines;
  if (t[0] == '#' || t[0] == ';' || t.rfind("//", 0) == 0) return;
  if (t[0] == '[' && t.find(']') != std::string::npos) {
    ++k.sections;
    const std::string name = import_trim(t.substr(1, t.find(']') - 1));
    k.machine_table = k.machine_table || name == "machine";
    k.printer_section = k.printer_section || name == "printer" || name.rfind("include ", 0) == 0;
    return;
  }
  bool echo = false;
  const std::string cmd = detect_gcode_command(t, echo);
  if (!cmd.empty()) {
    ++k.gcode;
    if (echo) ++k.echo;
    for (const char* c : {"m208", "m584", "m669", "m950", "m308", "m563", "m305", "m307", "m350"})
      if (cmd == c) ++k.rrf;
    return;
  }
  const auto sep = t.find_first_of(":=");
  if (sep != std::string::npos && t[sep] == ':') ++k.colon_options;
}

}  // namespace

std::string to_string(ConfigFormat f) {
  switch (f) {
    case ConfigFormat::profile_toml: return "toml";
    case ConfigFormat::klipper: return "klipper";
    case ConfigFormat::marlin_m503: return "marlin-m503";
    case ConfigFormat::marlin_config: return "marlin-configuration";
    case ConfigFormat::rrf: return "rrf";
  }
  return "toml";
}

ConfigFormat detect_config_format(const std::string& text, const std::string& path) {
  ImportLineKinds k;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) classify_line(line, k);
  if (k.nonblank == 0) throw InputError("the file is empty", path);
  if (k.defines > 0 && k.defines >= k.gcode && k.sections == 0) return ConfigFormat::marlin_config;
  if (k.sections > 0 && !k.machine_table && (k.colon_options > 0 || k.printer_section)) return ConfigFormat::klipper;
  if (k.sections > 0 || has_extension(path, ".toml")) return ConfigFormat::profile_toml;
  if (k.gcode > 0) {
    if (k.echo > 0) return ConfigFormat::marlin_m503;
    if (k.rrf > 0 || has_extension(path, ".g")) return ConfigFormat::rrf;
    return ConfigFormat::marlin_m503;
  }
  throw InputError(
      "neither a tunekit machine profile (TOML) nor a firmware configuration tunekit reads (a Klipper printer.cfg, "
      "a Marlin M503 report or Configuration.h, a RepRapFirmware config.g)",
      path);
}

bool is_firmware_configuration(const std::string& path) {
  if (has_extension(path, ".toml")) return false;
  try {
    return detect_config_format(read_file_head(path, std::uint64_t{1} << 20), path) != ConfigFormat::profile_toml;
  } catch (const Error&) {
    return false;
  }
}

namespace {

/// The imported profile as load_machine_profile() reads its TOML: the same checks as every TOML
/// profile, and the same defaults for what the TOML leaves out. What the TOML does not carry (the
/// sources, Klipper's acceleration in force) is kept.
MachineProfile as_loaded(const MachineProfile& imported, const std::string& path) {
  MachineProfile p;
  try {
    p = parse_machine_profile(machine_profile_toml(imported), path);
  } catch (const InputError& e) {
    throw InputError("the imported profile does not pass the machine profile's checks: " + e.message(), path);
  }
  p.sources = imported.sources;
  p.state.accel_in_force_mm_s2 = imported.state.accel_in_force_mm_s2;
  return p;
}

}  // namespace

MachineProfile import_machine_profile(const std::string& path, const ProfileImportOptions& options,
                                      std::string* bytes) {
  // The format's sniffing, the importer and the firmware's own parser each read the file by path:
  // opened once, the same bytes for all (and the includes of a Klipper configuration likewise).
  const core::InputReadScope read_once;
  std::string local;
  std::string& text = bytes != nullptr ? *bytes : local;
  text = read_file_bytes(path);
  const ConfigFormat f = has_extension(path, ".toml") ? ConfigFormat::profile_toml : detect_config_format(text, path);
  switch (f) {
    case ConfigFormat::profile_toml: return parse_machine_profile(text, path);
    case ConfigFormat::klipper: return as_loaded(profile_from_klipper(path, options), path);
    case ConfigFormat::marlin_m503:
    case ConfigFormat::marlin_config: return as_loaded(profile_from_marlin(path, options), path);
    case ConfigFormat::rrf: return as_loaded(profile_from_rrf(path, options), path);
  }
  return parse_machine_profile(text, path);
}

}  // namespace tunekit::machine
