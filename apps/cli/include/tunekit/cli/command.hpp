#pragma once
// The shape of every tunekit command, so that commands can use each other as functions:
//
//   XOptions                  what a user chooses; library option structs are members, so the
//                             command line binds straight to them and a default lives in one place
//   XOutcome compute_x(opts)  does the work and returns typed results; throws tunekit::Error
//                             (InputError, FitError, MachineError) with its exit code
//   Envelope to_envelope(o)   the JSON envelope (tunekit/calibration/results/envelope.hpp) the command writes
//   void print_text(o, os)    the human-readable summary
//   register_x(app, ctx)      binds XOptions to the command line (CLI11) and prints; nothing else
//
// `calibrate` and `batch` call compute_x() and read the typed outcome; no command runs another
// through argument strings.

#include <ostream>

#include "tunekit/calibration/results/context.hpp"
#include "tunekit/calibration/results/envelope.hpp"

namespace tunekit::cli {

/// What a command's callback does with an outcome: the text summary on ctx.out unless --json,
/// then the envelope where `output` says. Returns the process exit code (1 for an unmet
/// --require threshold).
template <class Outcome>
int report_outcome(const Outcome& outcome, const calibration::OutputOptions& output, calibration::CliContext& ctx) {
  if (!output.json) print_text(outcome, ctx.out);
  return calibration::emit(to_envelope(outcome), output, ctx);
}

}  // namespace tunekit::cli
