#include "tunekit/calibration/results/results_json.hpp"

#include <algorithm>

#include <fmt/format.h>

#include "tunekit/core/json_error_text.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/core/file_bytes.hpp"

namespace tunekit::calibration {
namespace {

/// Line and column (1-based) of byte offset `pos` in `text`.
std::pair<std::size_t, std::size_t> line_column_at(std::string_view text, std::size_t pos) {
  pos = std::min(pos, text.size());
  std::size_t line = 1, col = 1;
  for (std::size_t i = 0; i < pos; ++i) {
    if (text[i] == '\n') {
      ++line;
      col = 1;
    } else {
      ++col;
    }
  }
  return {line, col};
}

std::string results_json_location(const std::string& path, std::string_view text, std::size_t pos) {
  const auto [line, col] = line_column_at(text, pos);
  return source_location(path, line, col);
}

std::string member_location(const std::string& path, std::string_view text, std::string_view key) {
  const auto line = line_of_member(text, key);
  return line ? source_location(path, line) : path;
}

}  // namespace

std::size_t line_of_member(std::string_view text, std::string_view key) {
  const std::string quoted = fmt::format("\"{}\"", key);
  const auto at = text.find(quoted);
  if (at == std::string_view::npos) return 0;
  return line_column_at(text, at).first;
}

nlohmann::json parse_results_json(std::string_view text, const std::string& path) {
  try {
    return nlohmann::json::parse(text.begin(), text.end());
  } catch (const nlohmann::json::parse_error& e) {
    // e.byte is 1-based: the byte at which the parser stopped.
    const std::size_t pos = e.byte > 0 ? e.byte - 1 : 0;
    // "[json.exception.parse_error.101] parse error at line 1, column 1: syntax error while parsing
    // value - invalid literal; last read: 'g'": the location is ours, the rest says what is wrong.
    std::string what = e.what();
    if (const auto column = what.find(", column "); column != std::string::npos) {
      if (const auto colon = what.find(": ", column); colon != std::string::npos) what = what.substr(colon + 2);
    } else if (const auto bracket = what.find("] "); bracket != std::string::npos) {
      what = what.substr(bracket + 2);
    }
    throw InputError(fmt::format("not valid JSON: {}", what), results_json_location(path, text, pos));
  } catch (const nlohmann::json::out_of_range& e) {
    // "number overflow parsing '1e400'": a number beyond a double. Locate the number.
    std::string what = e.what();
    std::size_t pos = std::string::npos;
    if (const auto q = what.find('\''); q != std::string::npos) {
      const auto q2 = what.find('\'', q + 1);
      if (q2 != std::string::npos) pos = text.find(what.substr(q + 1, q2 - q - 1));
    }
    const std::string where = pos == std::string::npos ? path : results_json_location(path, text, pos);
    throw InputError("a number is beyond the range of a double (about 1.8e308)", where);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(fmt::format("not valid JSON: {}", core::plain_json_error(e.what())), path);
  }
}

nlohmann::json read_json_file(const std::string& path, std::string* bytes) {
  std::string text = read_file_bytes(path);
  auto j = parse_results_json(text, path);
  if (bytes != nullptr) *bytes = std::move(text);
  return j;
}

nlohmann::json read_results_json(const std::string& path, std::string* bytes) {
  std::string text;
  auto j = read_json_file(path, &text);
  check_results_envelope(j, text, path);
  if (bytes != nullptr) *bytes = std::move(text);
  return j;
}

void check_results_envelope(const nlohmann::json& j, std::string_view text, const std::string& path) {
  if (!j.is_object())
    throw InputError(fmt::format("a tunekit results file is a JSON object, not {}", j.type_name()), path);
  auto require = [&](const char* key, bool ok, const char* what) {
    if (j.contains(key) && !ok)
      throw InputError(fmt::format("\"{}\" must be {}, not {}", key, what, j[key].type_name()),
                       member_location(path, text, key));
  };
  require("command", j.contains("command") && j["command"].is_string(), "a string");
  require("results", j.contains("results") && j["results"].is_object(), "an object");
  require("options", j.contains("options") && j["options"].is_object(), "an object");
  require("diagnostics", j.contains("diagnostics") && j["diagnostics"].is_object(), "an object");
  require("warnings", j.contains("warnings") && j["warnings"].is_array(), "an array of strings");
  if (j.contains("warnings"))
    for (const auto& w : j["warnings"])
      if (!w.is_string())
        throw InputError(fmt::format("\"warnings\" must hold strings, not {}", w.type_name()),
                         member_location(path, text, "warnings"));
  require("tool", j.contains("tool") && j["tool"].is_object(), "an object");
  if (j.contains("tool") && j["tool"].contains("version") && !j["tool"]["version"].is_string())
    throw InputError("\"tool\".\"version\" must be a string", member_location(path, text, "version"));
}

}  // namespace tunekit::calibration
