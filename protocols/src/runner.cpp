#include "tunekit/protocols/runner.hpp"

#include "run_sessions.hpp"
#include "tunekit/machine/rrf_http.hpp"
#include "tunekit/ident/rrf_accelerometer.hpp"

#include <algorithm>
#include <ctime>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/core/atomic_file.hpp"
#include "tunekit/core/file_bytes.hpp"
#include "tunekit/firmware/dialect.hpp"
#include "tunekit/machine/journal.hpp"
#include "tunekit/machine/klipper_api.hpp"
#include "tunekit/machine/klipper_sensors.hpp"
#include "tunekit/protocols/feed_track_plan.hpp"
#include "tunekit/protocols/safety.hpp"
#include "tunekit/protocols/stop_signals.hpp"
#include "tunekit/machine/serial_transport.hpp"

namespace tunekit::protocols {
namespace {

using detail::Recorder;
using detail::Session;

std::string utc_stamp() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  ::gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y%m%d_%H%M%S", &tm);
  return buf;
}

std::string unique_dir(const std::string& base) {
  std::string d = base;
  for (int i = 2; std::filesystem::exists(d); ++i) d = fmt::format("{}-{}", base, i);
  return d;
}

/// The protocol's lines after ";@epilogue": what restores the machine's own settings.
std::vector<std::string> epilogue_lines(const std::vector<std::string>& gcode) {
  std::vector<std::string> out;
  bool in = false;
  for (const auto& l : gcode) {
    if (l == ";@epilogue") in = true;
    else if (in && !l.empty() && l[0] != ';') out.push_back(l.substr(0, l.find(';')));
  }
  return out;
}

std::string join_lines(const std::vector<std::string>& lines) {
  std::string s;
  for (const auto& l : lines) s += l + "\n";
  return s;
}

/// After the firmware is identified, before anything but the identification was sent: a profile
/// naming another firmware is refused (RunOptions::strict_firmware) or overridden with a warning;
/// the protocol is rebuilt for the firmware found, within the stricter of the profile's and the
/// firmware's limits, and checked again.
void adapt_to_firmware(const RunOptions& o, const machine::MachineProfile& profile, Session& session,
                       const std::string& port, machine::Journal& journal, nlohmann::json& summary, RunResult& res,
                       const std::function<void(const std::string&)>& progress) {
  const auto found = session.dialect.firmware();
  const auto named = firmware::firmware_from_name(profile.firmware);
  nlohmann::json warnings = nlohmann::json::array();
  if (!o.host && !profile.firmware.empty() && named != found &&
      session.firmware.firmware != firmware::Firmware::unknown) {
    const std::string what =
        fmt::format("the profile {} names the firmware '{}' but the machine on {} is {} {}", profile.name,
                    profile.firmware, port, session.firmware.name, session.firmware.version);
    if (o.strict_firmware)
      throw InputError(what + ": correct [machine] firmware in the profile (or leave it empty to identify it)");
    warnings.push_back(what + fmt::format("; the protocol is built for {}, the firmware found", to_string(found)));
  }
  std::vector<std::string> notes;
  const machine::MachineProfile run_profile = session.with_firmware_limits(profile, notes);
  for (const auto& n : notes) warnings.push_back("firmware setting: " + n);
  for (const auto& w : warnings) {
    progress("warning: " + w.get<std::string>());
    journal.event("warning", {{"message", w}});
  }
  if (!warnings.empty()) summary["warnings"] = warnings;
  res.experiment = build_experiment(o.protocol, o.params, o.axis, run_profile, session.dialect, o.limits);
  res.gcode = res.experiment.gcode;
  require_within_limits(res.gcode, run_profile, res.experiment.sensors, o.limits);
  summary["experiment"] = res.experiment.to_json();
  summary["dialect"] = to_string(found);
  core::write_file_atomic(journal.path("protocol.gcode"), join_lines(res.gcode));
  // The commanded feed as the firmware plans it, for the analysis (feed_track_plan.hpp).
  if (const auto track = planned_feed_track(res.experiment); !track.empty()) {
    core::write_file_atomic(journal.path("feed_track.csv"), ident::feed_track_csv(track));
    res.files[RunFile::feed_track] = journal.path("feed_track.csv");
  }
}

/// The dialect the protocol is planned in before the firmware answers: the host's (the simulated
/// printer's firmware) or the profile's firmware (Marlin when it names none). A dry run on a
/// printer plans for the M493 report its profile keeps ([firmware_state] m493_report).
firmware::Dialect planned_dialect(const RunOptions& o) {
  if (o.host) return o.host->planned_dialect();
  const auto& profile = o.profile;
  firmware::Dialect dialect(profile.firmware.empty() ? firmware::Firmware::marlin
                                                     : firmware::firmware_from_name(profile.firmware));
  if (dialect.firmware() == firmware::Firmware::marlin)
    dialect.set_ft_motion(firmware::parse_m493_report(profile.state.m493_report));
  return dialect;
}

/// The firmware the session identified, in the journal and the run's summary.
void note_firmware(const Session& session, machine::Journal& journal, nlohmann::json& summary, RunResult& res) {
  journal.event("firmware", {{"name", session.firmware.name},
                             {"version", session.firmware.version},
                             {"dialect", to_string(session.dialect.firmware())},
                             {"ft_motion", session.firmware.ft_motion},
                             {"ft_motion_active", session.firmware.ft_motion_active},
                             {"m493_form", to_string(m493_syntax(session.firmware.m493))}});
  summary["firmware"] = {{"name", session.firmware.name}, {"version", session.firmware.version}};
  if (session.firmware.ft_motion) {
    res.ft_motion = session.firmware.ft_motion_active ? "active" : "built, inactive";
    summary["firmware"]["ft_motion"] = res.ft_motion;
    res.m493_form = to_string(m493_syntax(session.firmware.m493));
    summary["firmware"]["m493_form"] = res.m493_form;
  }
}

/// The fan and feed the protocol commands from each piece of its thermal plan on (none for a
/// protocol without one): what a firmware's temperature reports do not state.
std::vector<Recorder::ThermalInput> thermal_inputs(const Experiment& e) {
  std::vector<Recorder::ThermalInput> out;
  if (e.excitation.contains("pieces"))
    for (const auto& p : e.excitation["pieces"])
      out.push_back({p.value("from_s", 0.0), p.value("fan_duty", 0.0), p.value("feed_mm_s", 0.0)});
  return out;
}

/// Fails before heating and homing when the link cannot record what the protocol needs.
void require_recordable(Session& session, const std::vector<std::string>& sensors, const std::string& port) {
  for (const auto& sensor : sensors)
    if (!session.can_record(sensor)) {
      const bool rrf = session.firmware.firmware == firmware::Firmware::reprapfirmware && sensor == "accelerometer";
      throw MachineError(
          fmt::format("the firmware ({}) cannot record {} data over this link ({}); nothing but M115 was sent",
                      session.firmware.name.empty() ? "unidentified" : session.firmware.name, sensor,
                      rrf ? "RepRapFirmware records its accelerometer with M956 into 0:/sys/accelerometer/ and offers "
                            "no way to read a file over USB serial (M28/M29 write, M20 lists, M36/M38 describe a "
                            "file); give the profile its web server, [network] http = \"http://HOST\", to fetch it "
                            "with rr_download"
                      : sensor == "heater"
                          ? "Marlin reports its temperatures by itself only when built with AUTO_REPORT_TEMPERATURES "
                            "(M115 Cap:AUTOREPORT_TEMP:1), and polling M105 cannot sample through the protocol's "
                            "dwells; Klipper's heaters and RepRapFirmware's object model are not read yet"
                          : "no tunekit sensor stream"),
          port);
    }
  for (const auto& sensor : sensors) session.check_recording(sensor);
}

/// Sends the protocol's lines in runs between its recording directives (";@record SENSOR on|off"),
/// each "on" with the planned machine time up to its "off".
void send_protocol(Session& session, const std::vector<std::string>& gcode, const std::atomic<bool>& abort_flag,
                   const std::string& port) {
  std::vector<std::string> run;  // the lines since the last recording directive
  const auto send_run = [&] {
    session.send_lines(run, abort_flag);
    run.clear();
  };
  for (const auto& line : gcode) {
    if (abort_flag.load()) throw MachineError("interrupted", port);
    if (line.rfind(";@record ", 0) == 0) {
      send_run();
      const auto rest = line.substr(9);
      const auto sp = rest.find(' ');
      const std::string sensor = rest.substr(0, sp);
      const bool on = rest.substr(sp + 1) == "on";
      double window_s = 0;
      if (on) {
        // The planned machine time up to this sensor's "off" directive.
        const auto here = gcode.begin() + (&line - gcode.data());
        const auto off = std::find(here, gcode.end(), ";@record " + sensor + " off");
        window_s = estimate_gcode_duration_s(std::vector<std::string>(here, off));
      }
      session.record(sensor, on, window_s);
      continue;
    }
    if (line.empty() || line[0] == ';') continue;
    std::string cmd = line.substr(0, line.find(';'));
    while (!cmd.empty() && cmd.back() == ' ') cmd.pop_back();
    run.push_back(std::move(cmd));
  }
  send_run();
}

/// The load cell's file: step.csv for the step tests (what `tunekit step` reads), else
/// feed_force.csv.
std::string load_cell_file(const std::string& protocol) {
  const Protocol id = protocol_spec(protocol).id;
  return id == Protocol::liquefier_step || id == Protocol::liquefier_flow_sweep ? "step.csv" : "feed_force.csv";
}

/// Whether the protocol sets a heater to a temperature above 0 (then the run turns the heaters
/// off at its end, unless RunOptions::keep_heaters).
bool heats(const std::vector<std::string>& gcode) {
  for (const auto& line : gcode) {
    const std::string cmd = line.substr(0, line.find(';'));
    const bool heater = cmd.rfind("M104", 0) == 0 || cmd.rfind("M109", 0) == 0 || cmd.rfind("M140", 0) == 0 ||
                        cmd.rfind("M190", 0) == 0 || cmd.rfind("SET_HEATER_TEMPERATURE", 0) == 0;
    if (!heater) continue;
    for (const std::string key : {" S", " R", " TARGET="})
      if (const auto at = cmd.find(key);
          at != std::string::npos && std::strtod(cmd.c_str() + at + key.size(), nullptr) > 0)
        return true;
  }
  return false;
}

/// The end of a run that heated: the heaters go back off (journaled as "heaters off").
void restore_heaters(Session& session, const std::vector<std::string>& gcode, bool keep, machine::Journal& journal,
                     const std::atomic<bool>& abort_flag) {
  if (!heats(gcode)) return;
  if (keep) {
    journal.event("heaters kept", {{"reason", "--keep-heaters"}});
    return;
  }
  const auto off = session.dialect.heaters_off();
  journal.event("heaters off", {{"commands", off}});
  session.send_lines(off, abort_flag);
}

/// After a failure or a stop: the firmware's stop and heaters off (as the profile says), then what
/// the protocol changed for its test, each journaled.
void send_safe_state(Session& session, const machine::MachineProfile& profile, const std::vector<std::string>& gcode,
                     machine::Journal& journal) {
  const auto safe = session.dialect.safe_state(profile.temperature.heaters_off_on_abort);
  journal.event("safe state", {{"commands", safe}});
  session.safe_state(safe);
  // Restore what the protocol changed for its test (after the stop). After an emergency
  // stop (M112) the firmware must be restarted, which reloads its configuration anyway.
  const auto restore = epilogue_lines(gcode);
  if (!restore.empty() && std::find(safe.begin(), safe.end(), "M112") == safe.end()) {
    journal.event("restore", {{"commands", restore}});
    session.safe_state(restore);
  }
}

/// Rewrites run.json of a run that had completed when a stop signal arrived: "interrupted", and
/// where it was.
void mark_interrupted(const std::string& run_json, const std::string& where) {
  nlohmann::json summary = nlohmann::json::parse(read_file_bytes(run_json), nullptr, false);
  if (summary.is_discarded()) summary = nlohmann::json::object();
  summary["status"] = "interrupted";
  summary["stopped_at"] = where;
  summary["error"] = "interrupted by " + StopSignals::received() + " " + where;
  core::write_file_atomic(run_json, summary.dump(2) + "\n");
}

/// The sensor records the run wrote, listed among its files.
void list_recorded_files(const machine::Journal& journal, const Recorder& rec, RunResult& res) {
  if (journal.has_csv(rec.load_file())) res.files[RunFile::load_cell] = journal.path(rec.load_file());
  if (journal.has_csv(rec.accel_file())) res.files[RunFile::accel] = journal.path(rec.accel_file());
  if (journal.has_csv(rec.commanded_file())) res.files[RunFile::commanded_accel] = journal.path(rec.commanded_file());
  if (journal.has_csv(rec.motion_file())) res.files[RunFile::commanded_motion] = journal.path(rec.motion_file());
  if (journal.has_csv(Recorder::kThermalFile)) res.files[RunFile::thermal] = journal.path(Recorder::kThermalFile);
}

/// The end of a run, complete or not: the samples and the link's statistics into the summary,
/// the session closed, the machine the host served stopped (its own files kept), the files listed and run.json
/// written.
void close_run(nlohmann::json& summary, std::unique_ptr<Session>& session, const Recorder& rec,
               machine::Journal& journal, ServedMachine* served, RunResult& res) {
  summary["samples"] = {{"load_cell", rec.load_samples()}, {"accel", rec.accel_samples()}};
  if (rec.thermal_samples() > 0) summary["samples"]["thermal"] = rec.thermal_samples();
  if (session) summary["link"] = session->stats();
  session.reset();
  if (served) served->stop(journal, res.files);
  list_recorded_files(journal, rec, res);
  summary["files"] = to_json(res.files);
  core::write_file_atomic(journal.path("run.json"), summary.dump(2) + "\n");
}

/// A run that failed or was stopped (`interrupted`) at `stage`: the journal and run.json say why
/// and where, the machine is brought to a safe state, and the error is thrown again naming where
/// the partial run is kept (an InterruptedError when a stop signal ended it).
[[noreturn]] void fail_run(const MachineError& e, bool interrupted, const std::string& stage,
                           std::unique_ptr<Session>& session, const machine::MachineProfile& profile,
                           nlohmann::json& summary, const Recorder& rec, machine::Journal& journal,
                           ServedMachine* served, RunResult& res) {
  const std::string signal = StopSignals::received();
  const MachineError why = interrupted && !signal.empty() ? MachineError("interrupted by " + signal, e.location()) : e;
  journal.error(why.formatted());
  if (session) send_safe_state(*session, profile, res.gcode, journal);
  journal.sync();
  summary["status"] = interrupted ? "interrupted" : "failed";
  summary["stopped_at"] = stage;
  summary["error"] = why.formatted();
  close_run(summary, session, rec, journal, served, res);
  if (interrupted && !signal.empty()) {
    StopSignals::report();
    throw InterruptedError(StopSignals::received_number(),
                           fmt::format("{} {} (the partial run is kept in {})", why.message(), stage, res.run_dir),
                           why.location());
  }
  throw MachineError(fmt::format("{} (the partial run is kept in {})", why.message(), res.run_dir), why.location());
}

}  // namespace

void throw_if_stopped_after_run(const RunResult& r, const std::string& where) {
  if (!StopSignals::flag().load() || StopSignals::received_number() == 0) return;
  if (r.files.count(RunFile::summary)) mark_interrupted(r.files.at(RunFile::summary), where);
  StopSignals::throw_if_stopped(r.run_dir.empty() ? where
                                                  : fmt::format("{} (the run is kept in {})", where, r.run_dir));
}

RunResult run_experiment(const RunOptions& o) {
  const machine::MachineProfile& profile = o.profile;
  if (!o.host && o.port.empty()) throw InputError("--port is needed with a machine profile (or use --machine sim)");
  const firmware::Dialect dialect = planned_dialect(o);

  RunResult res;
  res.experiment = build_experiment(o.protocol, o.params, o.axis, profile, dialect, o.limits);
  res.gcode = res.experiment.gcode;
  // The gate: nothing is opened or sent when the protocol exceeds the profile or the caps.
  require_within_limits(res.gcode, profile, res.experiment.sensors, o.limits);
  if (o.dry_run) {
    res.status = "dry-run";
    return res;
  }

  // SIGINT, SIGTERM and SIGHUP stop the run safely from here on (stop_signals.hpp).
  const StopSignals stop_signals;
  const std::atomic<bool>* abort_flag = o.abort_flag ? o.abort_flag : &StopSignals::flag();
  const std::string stamp = utc_stamp();
  res.run_dir = o.run_dir.empty() ? unique_dir(fmt::format("{}/{}-{}", o.runs_root, o.protocol, stamp)) : o.run_dir;
  machine::Journal journal(res.run_dir);
  const std::string axis_tag = res.experiment.axis.empty() ? "xy" : res.experiment.axis;
  const std::string tag = o.file_tag.empty() ? stamp : o.file_tag;
  Recorder rec(journal, load_cell_file(o.protocol), fmt::format("raw_data_{}_{}.csv", axis_tag, tag),
               fmt::format("commanded_accel_{}_{}.csv", axis_tag, tag),
               fmt::format("commanded_motion_{}_{}.csv", axis_tag, tag));
  res.files[RunFile::journal] = journal.path("journal.jsonl");
  res.files[RunFile::gcode] = journal.path("protocol.gcode");
  res.files[RunFile::summary] = journal.path("run.json");

  nlohmann::json summary{{"protocol", o.protocol},  {"experiment", res.experiment.to_json()}, {"machine", o.machine},
                         {"profile", profile.name}, {"profile_source", profile.source_path},  {"started_utc", stamp}};
  // The machine the host brings up for this run (the simulated printer), or the one on o.port.
  const std::unique_ptr<ServedMachine> served = o.host ? o.host->start(journal, res.files, o.port) : nullptr;
  const std::string port = served ? served->port() : o.port;
  summary["port"] = port;
  journal.event("start", {{"protocol", o.protocol}, {"port", port}, {"params", res.experiment.params}});
  auto progress = [&](const std::string& m) {
    if (o.progress) o.progress(m);
  };

  SendGuard guard(profile);  // the last check of every line, in the link
  std::unique_ptr<Session> session;
  std::string stage = "while connecting";  // where a stop or failure found the run (run.json "stopped_at")
  try {
    progress(fmt::format("connecting to {}", port));
    const bool api = port.rfind("unix:", 0) == 0;
    auto transport = machine::open_transport(port, o.baud);
    if (api) session = detail::make_klipper_session(std::move(transport), journal, rec, o.link, profile.sensors, guard);
    else
      session = detail::make_gcode_session(std::move(transport), journal, rec, o.link, abort_flag, guard,
                                           served ? served->http_url() : profile.http_address,
                                           machine::rrf_password(profile.http_password));
    stage = "while identifying the firmware";
    session->firmware = session->identify();
    session->dialect = firmware::Dialect(
        session->firmware.firmware == firmware::Firmware::unknown ? dialect.firmware() : session->firmware.firmware);
    session->dialect.set_ft_motion(session->firmware.m493);
    note_firmware(*session, journal, summary, res);
    adapt_to_firmware(o, profile, *session, port, journal, summary, res, progress);
    rec.set_thermal_inputs(thermal_inputs(res.experiment));
    require_recordable(*session, res.experiment.sensors, port);
    progress(fmt::format("firmware: {} {}; running {} ({} lines, ~{:.0f} s of machine time)", session->firmware.name,
                         session->firmware.version, o.protocol, res.gcode.size(), res.experiment.estimated_duration_s));
    stage = "while sending the protocol";
    send_protocol(*session, res.gcode, *abort_flag, port);
    stage = "after the protocol's last line, turning the heaters off";
    restore_heaters(*session, res.gcode, o.keep_heaters, journal, *abort_flag);
    stage = "after the protocol's last line, collecting the last samples";
    session->finish();
    // A stop that arrived once every line was answered still stops the run (stop_signals.hpp).
    if (abort_flag->load()) throw MachineError("interrupted", port);
  } catch (const MachineError& e) {
    fail_run(e, abort_flag->load(), stage, session, profile, summary, rec, journal, served.get(), res);
  }
  journal.event("end", {{"load_cell_samples", rec.load_samples()}, {"accel_samples", rec.accel_samples()}});
  journal.sync();
  summary["status"] = "complete";
  close_run(summary, session, rec, journal, served.get(), res);
  res.status = "complete";
  res.summary = summary;
  throw_if_stopped_after_run(res, "after the run had ended (every line answered; the machine was idle)");
  return res;
}

}  // namespace tunekit::protocols
