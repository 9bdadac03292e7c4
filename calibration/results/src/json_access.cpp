#include "tunekit/calibration/results/json_access.hpp"

#include <fmt/format.h>

#include "tunekit/core/error.hpp"

namespace tunekit::calibration {

const nlohmann::json* find_at(const nlohmann::json& root, const nlohmann::json::json_pointer& where) {
  // contains() never throws for a well-formed pointer: an array step that is not an index
  // ("/modes/x") or a step into a scalar is simply absent.
  try {
    if (!root.contains(where)) return nullptr;
    return &root.at(where);
  } catch (const nlohmann::json::out_of_range&) {
    return nullptr;  // an array index beyond any size_t
  }
}

const nlohmann::json& value_at_or_null(const nlohmann::json& root, const nlohmann::json::json_pointer& where) {
  static const nlohmann::json absent;
  const auto* v = find_at(root, where);
  return v != nullptr ? *v : absent;
}

nlohmann::json::json_pointer pointer_from_dotted(const std::string& path) {
  nlohmann::json::json_pointer p;
  std::size_t i = 0;
  while (i < path.size()) {
    if (path[i] == '.') {
      ++i;
      continue;
    }
    if (path[i] == '[') {
      const std::size_t close = path.find(']', i);
      const std::string index = close == std::string::npos ? std::string() : path.substr(i + 1, close - i - 1);
      if (index.empty() || index.size() > 18 || index.find_first_not_of("0123456789") != std::string::npos)
        throw InputError(fmt::format("'{}': an array index is a number in brackets, e.g. modes[0]", path));
      p /= static_cast<std::size_t>(std::stoull(index));
      i = close + 1;
      continue;
    }
    std::size_t end = path.find_first_of(".[", i);
    if (end == std::string::npos) end = path.size();
    p /= path.substr(i, end - i);
    i = end;
  }
  return p;
}

const nlohmann::json* json_at(const nlohmann::json& root, const std::string& path) {
  try {
    return find_at(root, pointer_from_dotted(path));
  } catch (const InputError&) {
    return nullptr;
  }
}

}  // namespace tunekit::calibration
