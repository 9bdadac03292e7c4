#pragma once
// Errors that carry the process exit code they map to:
// 0 ok, 1 fit failed or a requirement unmet, 2 usage or bad input, 3 machine or transport failure;
// 128 + N when a stop signal N ended a run (InterruptedError: 130 SIGINT, 143 SIGTERM, 129 SIGHUP).
// The CLI prints them as one line: `tunekit: error: LOCATION: message`.

#include <stdexcept>
#include <string>
#include <string_view>

namespace tunekit {

enum class ExitCode : int { ok = 0, fit_failed = 1, bad_input = 2, machine = 3 };

class Error : public std::runtime_error {
 public:
  /// `location` is empty or "FILE", "FILE:LINE" or "FILE:LINE:COLUMN". Both are kept as
  /// printable_message() makes them: an error quotes what a file held (a field, a column name,
  /// a firmware reply), and what it holds must not reach a terminal or a JSON document raw.
  Error(ExitCode code, std::string message, std::string location = {});
  ExitCode code() const noexcept { return code_; }
  const std::string& location() const noexcept { return location_; }
  const std::string& message() const noexcept { return message_; }
  /// The one-line form printed on stderr, without a trailing newline.
  std::string formatted() const;

 private:
  ExitCode code_;
  std::string message_;
  std::string location_;
};

/// Malformed, missing or implausible input (exit code 2).
class InputError : public Error {
 public:
  explicit InputError(std::string message, std::string location = {})
      : Error(ExitCode::bad_input, std::move(message), std::move(location)) {}
};

/// A fit that did not converge or whose parameters are not identifiable (exit code 1).
class FitError : public Error {
 public:
  explicit FitError(std::string message, std::string location = {})
      : Error(ExitCode::fit_failed, std::move(message), std::move(location)) {}
};

/// A machine or transport failure: no answer, disconnect, firmware error (exit code 3).
class MachineError : public Error {
 public:
  explicit MachineError(std::string message, std::string location = {})
      : Error(ExitCode::machine, std::move(message), std::move(location)) {}
};

/// A run stopped from outside by a signal (SIGINT, SIGTERM, SIGHUP): the exit code is the
/// shell's for a process ended by that signal, 128 + the signal's number (130, 143, 129), after
/// the machine was brought to its safe state and the run's files were written.
class InterruptedError : public Error {
 public:
  InterruptedError(int signal_number, std::string message, std::string location = {})
      : Error(static_cast<ExitCode>(128 + signal_number), std::move(message), std::move(location)) {}
};

/// `text` safe to print and to store as a JSON string: a control character other than a line
/// break or a tab (an escape sequence would drive the terminal), DEL, and every byte that is not
/// part of well-formed UTF-8 become "\xNN"; well-formed UTF-8 (a header's "Kraft (N)" or "°C")
/// is kept as it is.
std::string printable_message(std::string_view text);

/// "FILE:LINE" or "FILE:LINE:COLUMN" (a column of 0 is left out).
std::string source_location(const std::string& file, std::size_t line, std::size_t column = 0);

}  // namespace tunekit
