#pragma once
// A machine the runner brings up itself for each run rather than finding it on a port: the
// simulated printer, which calibration/ serves through this interface
// (tunekit/calibration/simulated_machine.hpp). The runner knows only the interface, so the
// protocols library needs no simulator.

#include <memory>
#include <string>

#include "tunekit/firmware/dialect.hpp"
#include "tunekit/machine/journal.hpp"
#include "tunekit/protocols/run_files.hpp"

namespace tunekit::protocols {

/// One run's machine, served in this process until stop().
class ServedMachine {
 public:
  virtual ~ServedMachine() = default;
  /// The device the runner opens (a pseudo-terminal).
  virtual std::string port() const = 0;
  /// The machine's web server, "http://127.0.0.1:PORT"; empty when it has none.
  virtual std::string http_url() const = 0;
  /// Stops serving, once the runner has closed its link, and keeps what the machine received and
  /// counted in the run directory (the files added to `files`).
  virtual void stop(machine::Journal& journal, RunFiles& files) = 0;
};

/// Brings up the machine of each run. Made once per command: what configures the machine is read
/// there, not for every run.
class MachineHost {
 public:
  virtual ~MachineHost() = default;
  /// The dialect the protocol is planned in before the firmware answers (what a dry run uses).
  virtual firmware::Dialect planned_dialect() const = 0;
  /// Once the run directory exists: keeps what is known of the machine there (the files added to
  /// `files`), then serves the machine for this run; with a `port` given, an outside
  /// link to the same machine, serves nothing and returns null.
  virtual std::unique_ptr<ServedMachine> start(machine::Journal& journal, RunFiles& files,
                                               const std::string& port) const = 0;
};

}  // namespace tunekit::protocols
