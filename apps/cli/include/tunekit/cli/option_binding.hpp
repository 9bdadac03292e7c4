#pragma once
// Binding a command-line word to a library enum (or flag) in place, so that the default shown
// by --help is the library's own default and no command restates it.

#include <cmath>
#include <cstdlib>
#include <string>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>

#include "tunekit/calibration/results/context.hpp"

namespace tunekit::cli {

/// A check for options that take a positive, finite number (a time, a budget, a factor): the
/// whole word must be the number. CLI11's PositiveNumber lets nan through (no comparison with
/// nan fails) and prints its range as a 309-digit number; this names the option's meaning.
inline CLI::Validator positive_finite(const std::string& what) {
  return CLI::Validator(
      [what](std::string& v) {
        char* end = nullptr;
        const double x = std::strtod(v.c_str(), &end);
        const bool ok = !v.empty() && end != nullptr && *end == '\0' && std::isfinite(x) && x > 0;
        return ok ? std::string() : "takes " + what + " (a positive, finite number), not '" + v + "'";
      },
      "POSITIVE");
}

/// Adds `--name WORD` that sets `target` to the value named by WORD. `choices` pairs each word
/// with its value; the default shown is the word of `target`'s current value. A word not in
/// `choices` is a usage error listing the words.
template <class T>
CLI::Option* add_choice_option(CLI::App* sub, const std::string& names, T& target,
                               const std::vector<std::pair<std::string, T>>& choices, const std::string& description) {
  std::string type = "TEXT:{";
  std::string current;
  for (std::size_t i = 0; i < choices.size(); ++i) {
    type += (i ? "," : "") + choices[i].first;
    if (current.empty() && choices[i].second == target) current = choices[i].first;
  }
  type += "}";
  auto* opt = sub->add_option_function<std::string>(
      names,
      [&target, choices, names](const std::string& word) {
        for (const auto& c : choices)
          if (c.first == word) {
            target = c.second;
            return;
          }
        std::string list;
        for (const auto& c : choices) list += (list.empty() ? "" : ", ") + c.first;
        throw CLI::ValidationError(names, "'" + word + "' is not one of " + list);
      },
      description);
  opt->type_name(type);
  if (!current.empty()) opt->default_str(current);
  return opt;
}

/// Adds `--name WORD` that sets `target` to parse(WORD), with the library's own parser (which
/// throws InputError for an unknown word) and name for the default shown by --help.
template <class T, class Parse, class Name>
CLI::Option* add_parsed_option(CLI::App* sub, const std::string& names, T& target, Parse parse, Name name,
                               const std::string& description) {
  auto* opt = sub->add_option_function<std::string>(
      names, [&target, parse](const std::string& word) { target = parse(word); }, description);
  opt->type_name("TEXT");
  opt->default_str(name(target));
  return opt;
}

/// Adds --feed-track FILE (tunekit step and freq): the commanded feed track for the whole-record
/// model, default feed_track.csv beside the log.
void add_feed_track_option(CLI::App* sub, std::string& target);

/// Adds --json, -o/--json-file and --require to a subcommand, and (unless `recordable` is
/// false) the history options --record, --machine-id and --db.
void add_output_options(CLI::App* sub, calibration::OutputOptions& o, bool recordable = true);

}  // namespace tunekit::cli
