#pragma once
// A bound on the nesting a dotted key or table header can ask for, checked on the TOML text
// before it is parsed.

#include <cstddef>
#include <string>
#include <string_view>

namespace tunekit::machine::detail {

/// The deepest dotted key or table header (`[a.b.c]`, `a.b.c = 1`) a machine profile may hold.
/// toml++ bounds the nesting of arrays and inline tables by TOML_MAX_NESTED_VALUES (256) but not
/// that of dotted keys, whose nested tables it builds and destroys recursively: 40,000 levels
/// exhaust the stack (Mark Gillard, toml++, toml++/impl/preprocessor.h, 2020-2024). The same
/// bound applies here; a machine profile nests two levels ([axes.x]).
inline constexpr std::size_t kMaxDottedKeyDepth = 256;

/// Throws InputError (located at the line) when a dotted key or table header of `text` has more
/// than kMaxDottedKeyDepth parts.
void check_dotted_key_depth(std::string_view text, const std::string& path);

}  // namespace tunekit::machine::detail
