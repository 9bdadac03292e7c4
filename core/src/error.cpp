#include "tunekit/core/error.hpp"

namespace tunekit {

Error::Error(ExitCode code, std::string message, std::string location)
    : std::runtime_error(location.empty() ? message : location + ": " + message),
      code_(code),
      message_(std::move(message)),
      location_(std::move(location)) {}

std::string Error::formatted() const {
  std::string s = "tunekit: error: ";
  if (!location_.empty()) s += location_ + ": ";
  s += message_;
  return s;
}

std::string source_location(const std::string& file, std::size_t line, std::size_t column) {
  std::string s = file + ":" + std::to_string(line);
  if (column > 0) s += ":" + std::to_string(column);
  return s;
}

}  // namespace tunekit
