#include "tunekit/core/input_read_scope.hpp"

namespace tunekit::core {
namespace {

// The live outermost scope of this thread, or null.
thread_local InputReadScope* live_scope = nullptr;

}  // namespace

InputReadScope::InputReadScope() {
  if (live_scope == nullptr) {
    live_scope = this;
    outermost_ = true;
  }
}

InputReadScope::~InputReadScope() {
  if (outermost_) live_scope = nullptr;
}

bool InputReadScope::active() { return live_scope != nullptr; }

std::optional<std::string> InputReadScope::cached(const std::string& path) {
  if (live_scope == nullptr) return std::nullopt;
  const auto it = live_scope->bytes_.find(path);
  if (it == live_scope->bytes_.end()) return std::nullopt;
  return it->second;
}

void InputReadScope::keep(const std::string& path, const std::string& bytes) {
  if (live_scope != nullptr) live_scope->bytes_[path] = bytes;
}

}  // namespace tunekit::core
