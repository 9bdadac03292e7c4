#pragma once
// Exact access to a member of a JSON value: nlohmann's json_pointer (RFC 6901,
// "/pooled/params/tau_s/value"), with a null answer when the member is absent instead of an
// exception. Results files name members with dotted paths ("compensators.settings.pa_k_s",
// "axes.x.modes[0].freq_hz": a key after each dot, an array index in brackets);
// pointer_from_dotted() turns such a path into a json_pointer, so there is one walker: nlohmann's.
// (The loose matching of --require paths is in requirements.hpp.)

#include <string>

#include <nlohmann/json.hpp>

namespace tunekit::calibration {

/// The member of `root` at `where`; nullptr when any step is missing (an absent key, an index
/// past the end, a step into a number or string).
const nlohmann::json* find_at(const nlohmann::json& root, const nlohmann::json::json_pointer& where);

/// *find_at(root, where), or a null JSON value when absent: for reading optional members and
/// testing their type in one expression.
const nlohmann::json& value_at_or_null(const nlohmann::json& root, const nlohmann::json::json_pointer& where);

/// "a.b[2].c" as the pointer /a/b/2/c (a key may hold '/' or '~'; the pointer escapes them).
/// Empty segments (".." or a leading '.') are skipped. Throws InputError (exit 2) for a
/// malformed index ("a[x]", "a[1").
nlohmann::json::json_pointer pointer_from_dotted(const std::string& path);

/// find_at(root, pointer_from_dotted(path)); nullptr also when `path` is malformed.
const nlohmann::json* json_at(const nlohmann::json& root, const std::string& path);

}  // namespace tunekit::calibration
