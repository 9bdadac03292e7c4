#pragma once
// Reading JSON files: tunekit's own results (the envelope of every command, results.json of a
// run directory, plotdata.json) for `tunekit export`, `report` and `history import`, and any
// other JSON input. Whatever the
// file holds, a problem is one located InputError (exit code 2), never an internal error:
// syntax errors and numbers beyond a double (1e400) at FILE:LINE:COLUMN, members of the wrong
// type ("command": 5, "results": null) at FILE:LINE of the member.

#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace tunekit::calibration {

/// Parses `text` (named `path` in messages). Throws InputError as described above.
nlohmann::json parse_results_json(std::string_view text, const std::string& path);

/// Every JSON file tunekit reads goes through here: parse_results_json() of the file's bytes
/// (syntax errors at FILE:LINE:COLUMN); an unreadable file is an InputError too. The bytes are
/// stored in *bytes when given (to record the input's digest without reading it twice).
nlohmann::json read_json_file(const std::string& path, std::string* bytes = nullptr);

/// read_json_file() and check_results_envelope(): a tunekit results envelope.
nlohmann::json read_results_json(const std::string& path, std::string* bytes = nullptr);

/// Checks the envelope members readers rely on: an object whose "command" (when present) is a
/// string, "results" an object, "warnings" an array of strings, "tool" an object with a string
/// "version", "options" an object. Throws InputError at the offending member's line.
void check_results_envelope(const nlohmann::json& j, std::string_view text, const std::string& path);

/// The 1-based line of the first occurrence of the member name `"key"` in `text` (0 if absent).
std::size_t line_of_member(std::string_view text, std::string_view key);

}  // namespace tunekit::calibration
