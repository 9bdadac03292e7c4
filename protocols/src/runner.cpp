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
#include "tunekit/sim/sim_camera.hpp"
#include "tunekit/machine/serial_transport.hpp"
#include "tunekit/sim/simulator.hpp"

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

/// The simulated Marlin build's answer to what identify() asks about FT_MOTION (M493, and M493 V
/// after a 2025-form report), for a dry run on the simulator.
firmware::FtMotionReport sim_m493_report(const sim::SimConfig& cfg) {
  if (cfg.ft_motion == "none") return {};
  sim::Simulator s(cfg);
  auto ask = [&s](const char* cmd) {
    std::string out;
    s.handle_line(cmd, [&out](std::string_view t) { out += t; });
    std::vector<std::string> lines;
    for (std::size_t b = 0, e; (e = out.find('\n', b)) != std::string::npos; b = e + 1)
      lines.push_back(out.substr(b, e - b));
    return lines;
  };
  auto answer = ask("M493");
  if (firmware::parse_m493_report(answer).form == firmware::M493Form::axis_list) {
    const auto v = ask("M493 V");
    answer.insert(answer.end(), v.begin(), v.end());
  }
  return firmware::parse_m493_report(answer);
}

/// After the firmware is identified, before anything but the identification was sent: a profile
/// naming another firmware is refused (RunOptions::strict_firmware) or overridden with a warning;
/// the protocol is rebuilt for the firmware found, within the stricter of the profile's and the
/// firmware's limits, and checked again.
void adapt_to_firmware(const RunOptions& o, bool sim, const machine::MachineProfile& profile, Session& session,
                       const std::string& port, machine::Journal& journal, nlohmann::json& summary, RunResult& res,
                       const std::function<void(const std::string&)>& progress) {
  const auto found = session.dialect.firmware();
  const auto named = firmware::firmware_from_name(profile.firmware);
  nlohmann::json warnings = nlohmann::json::array();
  if (!sim && !profile.firmware.empty() && named != found && session.firmware.firmware != firmware::Firmware::unknown) {
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
    res.files["feed_track"] = journal.path("feed_track.csv");
  }
}

/// The dialect the protocol is planned in before the firmware answers: the simulator's "firmware="
/// option (Marlin by default) or the profile's firmware. A dry run on the simulator plans for the
/// simulated build's M493 report (what identify() reads), on a printer for the report its profile
/// keeps ([firmware_state] m493_report).
firmware::Dialect planned_dialect(bool sim, const sim::SimConfig& sim_cfg, const machine::MachineProfile& profile) {
  const std::string fw_name = sim ? sim_cfg.firmware : profile.firmware;
  firmware::Dialect dialect(fw_name.empty() ? firmware::Firmware::marlin : firmware::firmware_from_name(fw_name));
  if (dialect.firmware() == firmware::Firmware::marlin)
    dialect.set_ft_motion(sim ? sim_m493_report(sim_cfg) : firmware::parse_m493_report(profile.state.m493_report));
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

/// Stops the simulator and keeps what it received and counted beside the run's data.
void stop_sim_and_keep_record(sim::SimPtyServer& server, machine::Journal& journal, RunResult& res) {
  server.stop();
  server.wait();
  const auto received = server.sim().received();
  core::write_file_atomic(journal.path("sim_received.gcode"), join_lines(received));
  core::write_file_atomic(journal.path("sim_stats.json"),
                          nlohmann::json{{"lines_received", received.size()},
                                         {"accel_samples_sent", server.sim().accel_samples_sent()},
                                         {"load_cell_samples_sent", server.sim().load_cell_samples_sent()},
                                         {"disconnected", server.disconnected()},
                                         {"halted", server.sim().halted()},
                                         {"machine_time_s", server.sim().time_s()}}
                                  .dump(2) +
                              "\n");
  res.files["sim_received"] = journal.path("sim_received.gcode");
}

/// The profile the run is checked against (RunOptions::profile, profile_path, machine).
machine::MachineProfile run_profile(const RunOptions& o, bool sim) {
  if (o.profile) return *o.profile;
  if (sim) return o.profile_path.empty() ? builtin_sim_profile() : machine::load_machine_profile(o.profile_path);
  if (!o.profile_path.empty() && o.profile_path != o.machine)
    throw InputError(
        "a real machine's profile is --machine FILE; --profile describes the printer --machine sim simulates");
  return machine::load_machine_profile(o.machine);
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

/// The simulated printer of a run on the simulator with no port given: served on a new
/// pseudo-terminal, its deposits on the simulated print bed when there is one.
std::unique_ptr<sim::SimPtyServer> serve_simulator(const sim::SimConfig& sim_cfg,
                                                   const std::shared_ptr<sim::SimPrintBed>& sim_bed) {
  std::function<void(sim::Simulator&)> setup;
  if (sim_bed)
    setup = [bed = sim_bed](sim::Simulator& s) {
      s.deposit_sink = [bed](double t, const std::array<double, 4>& pos, double v, double q) {
        bed->deposit(t, pos, v, q);
      };
    };
  return std::make_unique<sim::SimPtyServer>(sim_cfg, setup);
}

/// The sensor records the run wrote, listed among its files.
void list_recorded_files(const machine::Journal& journal, const Recorder& rec, RunResult& res) {
  if (journal.has_csv(rec.load_file())) res.files["load_cell"] = journal.path(rec.load_file());
  if (journal.has_csv(rec.accel_file())) res.files["accel"] = journal.path(rec.accel_file());
  if (journal.has_csv(rec.commanded_file())) res.files["commanded_accel"] = journal.path(rec.commanded_file());
  if (journal.has_csv(rec.motion_file())) res.files["commanded_motion"] = journal.path(rec.motion_file());
}

/// The end of a run, complete or not: the samples and the link's statistics into the summary,
/// the session closed, the simulator stopped (its record kept), the files listed and run.json
/// written.
void close_run(nlohmann::json& summary, std::unique_ptr<Session>& session, const Recorder& rec,
               machine::Journal& journal, sim::SimPtyServer* server, RunResult& res) {
  summary["samples"] = {{"load_cell", rec.load_samples()}, {"accel", rec.accel_samples()}};
  if (session) summary["link"] = session->stats();
  session.reset();
  if (server) stop_sim_and_keep_record(*server, journal, res);
  list_recorded_files(journal, rec, res);
  summary["files"] = res.files;
  core::write_file_atomic(journal.path("run.json"), summary.dump(2) + "\n");
}

/// A run that failed or was stopped (`interrupted`) at `stage`: the journal and run.json say why
/// and where, the machine is brought to a safe state, and the error is thrown again naming where
/// the partial run is kept (an InterruptedError when a stop signal ended it).
[[noreturn]] void fail_run(const MachineError& e, bool interrupted, const std::string& stage,
                           std::unique_ptr<Session>& session, const machine::MachineProfile& profile,
                           nlohmann::json& summary, const Recorder& rec, machine::Journal& journal,
                           sim::SimPtyServer* server, RunResult& res) {
  const std::string signal = StopSignals::received();
  const MachineError why = interrupted && !signal.empty() ? MachineError("interrupted by " + signal, e.location()) : e;
  journal.error(why.formatted());
  if (session) send_safe_state(*session, profile, res.gcode, journal);
  journal.sync();
  summary["status"] = interrupted ? "interrupted" : "failed";
  summary["stopped_at"] = stage;
  summary["error"] = why.formatted();
  close_run(summary, session, rec, journal, server, res);
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
  if (r.files.count("summary")) mark_interrupted(r.files.at("summary"), where);
  StopSignals::throw_if_stopped(r.run_dir.empty() ? where
                                                  : fmt::format("{} (the run is kept in {})", where, r.run_dir));
}

RunResult run_experiment(const RunOptions& o) {
  const bool sim = o.machine == "sim";
  const machine::MachineProfile profile = run_profile(o, sim);
  // Bad simulator options fail before anything else; the simulated printer is the profile's.
  const sim::SimConfig sim_cfg =
      sim ? sim::SimConfig::for_machine(profile, o.sim_options) : sim::SimConfig::from_options(o.sim_options);
  if (!sim && o.port.empty()) throw InputError("--port is needed with a machine profile (or use --machine sim)");
  const firmware::Dialect dialect = planned_dialect(sim, sim_cfg, profile);

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
  Recorder rec(
      journal, o.protocol == "liquefier-step" || o.protocol == "liquefier-flow-sweep" ? "step.csv" : "feed_force.csv",
      fmt::format("raw_data_{}_{}.csv", axis_tag, tag), fmt::format("commanded_accel_{}_{}.csv", axis_tag, tag),
      fmt::format("commanded_motion_{}_{}.csv", axis_tag, tag));
  res.files["journal"] = journal.path("journal.jsonl");
  res.files["gcode"] = journal.path("protocol.gcode");
  res.files["summary"] = journal.path("run.json");

  nlohmann::json summary{
      {"protocol", o.protocol},  {"experiment", res.experiment.to_json()}, {"machine", sim ? "sim" : o.machine},
      {"profile", profile.name}, {"profile_source", profile.source_path},  {"started_utc", stamp}};
  std::unique_ptr<sim::SimPtyServer> server;
  std::string port = o.port;
  if (sim) {
    core::write_file_atomic(journal.path("truth.json"), sim_cfg.truth().dump(2) + "\n");
    res.files["truth"] = journal.path("truth.json");
    if (port.empty()) {
      server = serve_simulator(sim_cfg, o.sim_bed);
      port = server->path();
    }
  }
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
                                           server ? server->http_url() : profile.http_address,
                                           machine::rrf_password(profile.http_password));
    stage = "while identifying the firmware";
    session->firmware = session->identify();
    session->dialect = firmware::Dialect(
        session->firmware.firmware == firmware::Firmware::unknown ? dialect.firmware() : session->firmware.firmware);
    session->dialect.set_ft_motion(session->firmware.m493);
    note_firmware(*session, journal, summary, res);
    adapt_to_firmware(o, sim, profile, *session, port, journal, summary, res, progress);
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
    fail_run(e, abort_flag->load(), stage, session, profile, summary, rec, journal, server.get(), res);
  }
  journal.event("end", {{"load_cell_samples", rec.load_samples()}, {"accel_samples", rec.accel_samples()}});
  journal.sync();
  summary["status"] = "complete";
  close_run(summary, session, rec, journal, server.get(), res);
  res.status = "complete";
  res.summary = summary;
  throw_if_stopped_after_run(res, "after the run had ended (every line answered; the machine was idle)");
  return res;
}

}  // namespace tunekit::protocols
