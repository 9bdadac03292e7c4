#pragma once
// Marlin's Configuration.h and Configuration_adv.h as the preprocessor sees the settings in them
// (MarlinFirmware, Marlin 2.1, Marlin/src/core/macros.h for the condition macros, 2011-2026):
// the active `#define NAME value` lines, with `#if`/`#ifdef`/`#ifndef`/`#elif`/`#else`/`#endif`
// followed and `#undef` applied, and the values evaluated as the arithmetic expressions they are.

#include <map>
#include <string>

#include "profile_import_detail.hpp"

namespace tunekit::machine::detail {

struct MarlinDefine {
  std::string value;  ///< the text after the name, comments dropped (empty for a flag)
  Site site;
};
using MarlinDefines = std::map<std::string, MarlinDefine>;

/// Reads the active defines of a header into `defines` (the first definition of a name wins;
/// `//#define` lines and block comments are not active). Conditions use Marlin's macros ENABLED,
/// DISABLED, ANY, ALL, BOTH, EITHER, NONE, `defined`, `!`, `&&`, `||`, parentheses and numeric
/// comparisons; one it cannot evaluate counts as true for each of its branches, so that the first
/// branch's definition wins.
void read_marlin_defines(const std::string& path, MarlinDefines& defines);

/// Marlin's ENABLED(name): defined as nothing, 1 or true.
bool marlin_enabled(const MarlinDefines& defines, const std::string& name);

/// The value of an expression of numbers (an f, F, L or U suffix allowed), other defines, + - * /,
/// parentheses and casts such as double(...). InputError at `site` for anything else.
double eval_marlin_expression(const MarlinDefines& defines, const std::string& text, const Site& site);

}  // namespace tunekit::machine::detail
