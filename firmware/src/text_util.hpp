#pragma once
// Configuration-line helpers shared by the G-code dialect and firmware-configuration parsers
// (private to the protocols library).

#include "tunekit/core/text.hpp"  // core::lower for configuration keys and G-code words

namespace tunekit::firmware::text {

/// A blank inside a configuration line: space or tab.
inline bool is_blank(char c) { return c == ' ' || c == '\t'; }

}  // namespace tunekit::firmware::text
