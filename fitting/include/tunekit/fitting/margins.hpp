#pragma once
// Equivalence margins: how large a change of a quantity has to be before it changes what a
// compensator does with it. Two estimates of a quantity "do not agree", and a machine's
// quantity "drifted", only when the 95 % interval of their difference lies wholly beyond the
// margin (a test of practical difference, not of equality: Wellek, "Testing Statistical
// Hypotheses of Equivalence and Noninferiority", 2010, chapter 1). A difference whose interval
// lies wholly inside the margin shows the two are equivalent; anything else is undecided.
//
// The margin is relative to the quantity's magnitude and chosen per kind of quantity (the last
// part of its history name: "x.freq_hz" is a frequency, "freq.tau_s" a time constant); why
// each value is what it is is in the `basis` sentence and in docs/history.md. A quantity that
// is designed, not measured (a shaper's frequency and maximum acceleration, the advance), has
// no margin of its own: it drifts only through the measured quantities it was designed from.

#include <string>
#include <vector>

namespace tunekit::fitting {

struct Margin {
  std::string kind;       ///< "time constant", "resonance frequency", ... ("designed" for designed ones)
  double relative = 0;    ///< the margin as a fraction of |value| (0.02 = 2 %); 0 for designed quantities
  bool designed = false;  ///< designed from other quantities: never flagged on its own
  std::string basis;      ///< one sentence: why this margin
  std::vector<std::string> designed_from;  ///< for a designed quantity: the history names it follows
};

/// The margin of the quantity with history name `name` (see tunekit/history/quantities.hpp).
/// Quantities of an unknown kind get a 5 % margin.
Margin equivalence_margin(const std::string& name);

/// Where the interval [d - h, d + h] of a difference d (half-width h >= 0) lies against the
/// margin m >= 0: wholly beyond it (+1), wholly within it (-1), or neither (0).
int beyond_margin(double difference, double half_width, double margin);

}  // namespace tunekit::fitting
