#include "tunekit/core/json_error_text.hpp"

#include <array>
#include <utility>

#include <fmt/format.h>

namespace tunekit::core {
namespace {

// nlohmann::json's type names (basic_json::type_name()) as a user would say them.
std::string value_kind(std::string_view type_name) {
  static constexpr std::array<std::pair<std::string_view, std::string_view>, 8> kKinds{{{"number", "a number"},
                                                                                        {"string", "text"},
                                                                                        {"boolean", "true or false"},
                                                                                        {"null", "null"},
                                                                                        {"object", "an object"},
                                                                                        {"array", "a list"},
                                                                                        {"binary", "binary data"},
                                                                                        {"discarded", "nothing"}}};
  for (const auto& [name, kind] : kKinds)
    if (type_name == name) return std::string(kind);
  return std::string(type_name);
}

// `text` after `prefix` when it starts with it.
bool consume(std::string_view& text, std::string_view prefix) {
  if (text.substr(0, prefix.size()) != prefix) return false;
  text.remove_prefix(prefix.size());
  return true;
}

// The text between the first pair of single quotes ("key 'model' not found" -> "model").
std::string_view quoted(std::string_view text) {
  const auto a = text.find('\'');
  const auto b = a == std::string_view::npos ? a : text.find('\'', a + 1);
  return b == std::string_view::npos ? text : text.substr(a + 1, b - a - 1);
}

// The library's sentences rephrased (nlohmann::json 3.x, detail/exceptions.hpp wordings).
std::string rephrase(std::string_view text) {
  std::string_view rest = text;
  if (consume(rest, "type must be ")) {
    const auto but = rest.find(", but is ");
    if (but != std::string_view::npos)
      return fmt::format("{} was expected, but found {}", value_kind(rest.substr(0, but)),
                         value_kind(rest.substr(but + 9)));
  }
  if (consume(rest, "cannot use ")) {
    const auto with = rest.rfind(" with ");
    if (with != std::string_view::npos)
      return fmt::format("the structure is not as expected: found {}", value_kind(rest.substr(with + 6)));
  }
  if (text.substr(0, 4) == "key " && text.find("not found") != std::string_view::npos)
    return fmt::format("the member '{}' is missing", quoted(text));
  if (consume(rest, "array index ")) return fmt::format("a list has no item {}", rest.substr(0, rest.find(' ')));
  if (text.find("number overflow") != std::string_view::npos)
    return fmt::format("the number {} is beyond the range of a double", quoted(text));
  if (consume(rest, "parse error")) {
    // "parse error at line 1, column 2: syntax error while parsing value - invalid literal; ..."
    const auto dash = rest.find(" - ");
    const auto colon = rest.find(": ");
    if (dash != std::string_view::npos && colon != std::string_view::npos && colon < dash)
      return fmt::format("syntax error{}: {}", rest.substr(0, colon), rest.substr(dash + 3));
    return fmt::format("syntax error{}", rest);
  }
  return std::string(text);
}

}  // namespace

std::string plain_json_error(std::string_view what) {
  std::string_view text = what;
  std::string where;
  if (consume(text, "[json.exception.")) {
    const auto close = text.find("] ");
    text.remove_prefix(close == std::string_view::npos ? text.size() : close + 2);
  }
  // With JSON_DIAGNOSTICS the library names the value's place: "(/axes/x) type must be ...".
  if (!text.empty() && text.front() == '(') {
    const auto close = text.find(") ");
    if (close != std::string_view::npos) {
      where = fmt::format(" (at {})", text.substr(1, close - 1));
      text.remove_prefix(close + 2);
    }
  }
  return rephrase(text) + where;
}

std::string plain_filesystem_error(std::string_view what) {
  constexpr std::string_view kTag = "filesystem error: ";
  if (what.substr(0, kTag.size()) == kTag) what.remove_prefix(kTag.size());
  // The paths follow in brackets: "WHAT [first] [second]".
  const auto first = what.find(" [");
  std::string paths;
  for (auto open = first; open != std::string_view::npos; open = what.find(" [", open + 2)) {
    const auto close = what.find(']', open);
    if (close == std::string_view::npos) break;
    paths += (paths.empty() ? "" : ", ") + std::string(what.substr(open + 2, close - open - 2));
  }
  const std::string text(what.substr(0, first));
  return paths.empty() ? text : paths + ": " + text;
}

}  // namespace tunekit::core
