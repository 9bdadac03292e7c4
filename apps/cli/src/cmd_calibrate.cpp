// tunekit calibrate: the technician's one command. It checks every experiment against the
// machine profile before anything is sent, runs them (liquefier step test, liquefier chirp,
// axis sweeps of X and Y), identifies the models with the same commands a user would run by
// hand (step, freq, shaper -- in-process, on the CSV files the run wrote), designs pressure
// advance and input shaping, previews the firmware configuration change, and writes a run
// directory:
//   RUN_DIR/results.json     the envelope: every identified value, compensators, summary
//   RUN_DIR/plotdata.json    the series behind the report's plots
//   RUN_DIR/report.html      one self-contained page (rebuild with `tunekit report RUN_DIR`)
//   RUN_DIR/<experiment>/    each experiment's journal, raw CSV data and (sim) truth.json
//   RUN_DIR/analysis/*.json  each analysis command's own JSON
//   RUN_DIR/config/          the configuration before and after, and the diff
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>

#include <fmt/format.h>

#include "tunekit/cli/commands.hpp"
#include "tunekit/cli/envelope.hpp"
#include "tunekit/cli/history_record.hpp"
#include "tunekit/cli/progress.hpp"
#include "tunekit/cli/report.hpp"
#include "tunekit/fitting/error.hpp"
#include "tunekit/fitting/first_order.hpp"
#include "tunekit/ident/csv.hpp"
#include "tunekit/ident/input_shaper.hpp"
#include "tunekit/protocols/atomic_file.hpp"
#include "tunekit/protocols/runner.hpp"

#ifndef TUNEKIT_DATASETS_DIR
#define TUNEKIT_DATASETS_DIR "datasets"
#endif

namespace tunekit::cli {
namespace {

namespace fs = std::filesystem;

struct CalibrateArgs {
  std::string machine = "sim";
  std::string profile;
  std::string port;
  std::string out_dir;
  std::string firmware = "klipper";
  std::string config;
  bool write = false;
  bool skip_liquefier = false;
  bool skip_axes = false;
  std::vector<std::string> sim_options;
  OutputOptions output;
};

struct Experiment {
  std::string name;      // sub-directory and label
  std::string protocol;  // protocols::protocol_specs() name
  std::string axis;
};

nlohmann::json parse_json_file(const std::string& path) {
  try {
    return nlohmann::json::parse(ident::read_file_bytes(path));
  } catch (const nlohmann::json::parse_error& e) {
    throw InputError(std::string("not valid JSON: ") + e.what(), path);
  }
}

// Runs an analysis command in-process, exactly as a user would on the command line, writing
// its JSON envelope to `json_path`. Errors keep their own message and exit code.
nlohmann::json analyze(const std::vector<std::string>& args, const std::string& json_path, CliContext& ctx) {
  std::vector<std::string> full = args;
  full.insert(full.end(), {"-o", json_path});
  std::ostringstream out, err;
  const int code = run_cli(full, out, err);
  if (code != 0) {
    std::string msg = err.str();
    while (!msg.empty() && msg.back() == '\n') msg.pop_back();
    const std::string prefix = "tunekit: error: ";
    if (msg.rfind(prefix, 0) == 0) msg = msg.substr(prefix.size());
    const std::string what = fmt::format("'tunekit {}' failed: {}", args.front(), msg);
    if (code == static_cast<int>(ExitCode::fit_failed)) throw FitError(what);
    throw InputError(what);
  }
  if (ctx.verbosity > 0) ctx.err << out.str();
  return parse_json_file(json_path);
}

double num(const nlohmann::json& j, const std::string& path) {
  const auto* v = json_at(j, path);
  return (v != nullptr && v->is_number()) ? v->get<double>() : std::nan("");
}

// Series for the step plot: the measured record and each step's own fitted model.
nlohmann::json step_plotdata(const std::string& csv, const nlohmann::json& step_results) {
  const auto table = ident::read_csv(csv, {{"time", "feed", "force"}, "time"});
  const auto& t = table.column("time").values;
  const auto& u = table.column("feed").values;
  const auto& y = table.column("force").values;
  std::vector<double> yf(t.size(), std::nan(""));
  const auto& steps = step_results.at("steps");
  for (std::size_t k = 0; k < steps.size(); ++k) {
    const auto& s = steps[k];
    if (!s.contains("params")) continue;
    const double ts = s.value("t_step_s", 0.0);
    const double t_next = k + 1 < steps.size() ? steps[k + 1].value("t_step_s", t.back() + 1) : t.back() + 1;
    // Before the first step only its own steady state is modelled (the warm-up is not).
    const double t_prev = k > 0 ? ts : ts - 0.5 * (t_next - ts);
    const double du = s.value("u_after", 0.0) - s.value("u_before", 0.0);
    const auto& p = s["params"];
    const double K = num(p, "K.value"), tau = num(p, "tau_s.value"), y0 = num(p, "y0.value");
    double theta = num(p, "theta_s.value");
    if (!std::isfinite(theta)) theta = 0;
    for (std::size_t i = 0; i < t.size(); ++i)
      if (t[i] >= t_prev && t[i] < t_next) yf[i] = fitting::step_response(t[i], ts, du, K, tau, theta, y0);
  }
  // Thin very long records for the plot (every n-th sample).
  const std::size_t stride = std::max<std::size_t>(1, t.size() / 4000);
  nlohmann::json d{{"u_label", "feed (mm/s)"}, {"y_label", "force (N)"}};
  std::vector<double> ts, us, ys, fs_;
  for (std::size_t i = 0; i < t.size(); i += stride) {
    ts.push_back(t[i]);
    us.push_back(u[i]);
    ys.push_back(y[i]);
    fs_.push_back(yf[i]);
  }
  d["t_s"] = ts;
  d["u"] = us;
  d["y"] = ys;
  d["y_fit"] = fs_;
  return d;
}

nlohmann::json bode_plotdata(const nlohmann::json& freq_results) {
  nlohmann::json d;
  const auto& b = freq_results.at("h1").at("bode");
  d["freq_hz"] = b.at("freq_hz");
  d["mag_db"] = b.at("magnitude_db");
  d["phase_deg"] = b.at("phase_deg");
  if (b.contains("coherence")) d["coherence"] = b["coherence"];
  if (freq_results.contains("tf_fit") && freq_results["tf_fit"].contains("bode")) {
    const auto& m = freq_results["tf_fit"]["bode"];
    d["model"] = {{"freq_hz", m.at("freq_hz")}, {"mag_db", m.at("magnitude_db")}, {"phase_deg", m.at("phase_deg")}};
  }
  return d;
}

nlohmann::json psd_plotdata(const nlohmann::json& axis) {
  nlohmann::json d;
  const auto& psd = axis.at("psd");
  d["freq_hz"] = psd.at("freq_hz");
  d["psd"] = psd.at("psd");
  d["modes"] = nlohmann::json::array();
  double zeta = 0.1;
  for (const auto& m : axis.value("modes", nlohmann::json::array())) {
    d["modes"].push_back({{"freq_hz", m.value("freq_hz", 0.0)}});
  }
  if (axis.contains("zeta") && axis["zeta"].is_number()) zeta = axis["zeta"].get<double>();
  // Each candidate shaper's remaining vibration against frequency, at the identified damping.
  std::vector<double> f = psd.at("freq_hz").get<std::vector<double>>();
  d["shapers"] = nlohmann::json::array();
  for (const auto& c : axis.value("candidates", nlohmann::json::array())) {
    const auto type = ident::parse_shaper_type(c.at("type").get<std::string>());
    const auto shaper = ident::design_shaper(type, c.at("freq_hz").get<double>(), c.value("damping", 0.1));
    d["shapers"].push_back({{"type", c.at("type")}, {"freq_hz", f}, {"response", ident::residual_vibration_curve(shaper, f, zeta)}});
  }
  return d;
}

// Paths inside the run directory are written relative to it, so that results.json does not
// depend on where the run lives (and two runs of one machine are byte-identical).
void strip_prefix(nlohmann::json& j, const std::string& prefix) {
  if (j.is_string()) {
    std::string s = j.get<std::string>();
    for (std::size_t pos; (pos = s.find(prefix)) != std::string::npos;) s.erase(pos, prefix.size());
    j = s;
  } else if (j.is_structured()) {
    for (auto& v : j) strip_prefix(v, prefix);
  }
}

std::string utc_stamp() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y%m%d-%H%M%S", &tm);
  return buf;
}

int run_calibrate(const CalibrateArgs& a, CliContext& ctx) {
  const bool sim = a.machine == "sim";
  if (!sim && a.profile.empty())
    throw InputError("a real machine needs its profile: --profile FILE (limits and sensors; see datasets/machines/sim.toml)");
  const std::string profile_path = !a.profile.empty() ? a.profile : std::string(TUNEKIT_DATASETS_DIR) + "/machines/sim.toml";
  const auto profile = !a.profile.empty() ? protocols::load_machine_profile(a.profile) : protocols::builtin_sim_profile();

  std::vector<Experiment> exps;
  if (!a.skip_liquefier) {
    if (!profile.sensors.load_cell) throw InputError("the liquefier tests need a load cell ([sensors] load_cell = true)", profile_path);
    exps.push_back({"liquefier-step", "liquefier-step", ""});
    exps.push_back({"liquefier-chirp", "liquefier-chirp", ""});
  }
  if (!a.skip_axes) {
    if (!profile.sensors.accelerometer) throw InputError("the axis sweeps need an accelerometer ([sensors] accelerometer = true)", profile_path);
    exps.push_back({"axis-x", "axis-sweep", "x"});
    exps.push_back({"axis-y", "axis-sweep", "y"});
  }
  if (exps.empty()) throw InputError("nothing to calibrate: both --skip-liquefier and --skip-axes were given");
  OutputOptions output = a.output;
  prepare_record(output, profile.id);  // --record: a bad machine id or database fails before the machine moves

  // Each calibration keeps its own run directory: a used one is never written into again.
  std::string run_dir = a.out_dir;
  if (run_dir.empty()) {
    const std::string base = "runs/calibrate-" + utc_stamp();
    run_dir = base;
    for (int k = 2; fs::exists(run_dir); ++k) run_dir = base + "-" + std::to_string(k);
  } else if (fs::exists(run_dir) && !(fs::is_directory(run_dir) && fs::is_empty(run_dir))) {
    throw InputError("the run directory already exists; give a new --out (or leave it out for runs/calibrate-UTCSTAMP)",
                     run_dir);
  }
  fs::create_directories(run_dir + "/analysis");
  fs::create_directories(run_dir + "/config");

  auto options_for = [&](const Experiment& e, bool dry) {
    protocols::RunOptions o;
    o.protocol = e.protocol;
    o.axis = e.axis.empty() ? "x" : e.axis;
    o.machine = sim ? "sim" : a.profile;
    o.port = a.port;
    o.sim_options = a.sim_options;
    o.dry_run = dry;
    o.run_dir = run_dir + "/" + e.name;
    o.file_tag = "tunekit";  // raw_data_x_tunekit.csv: names that do not change from run to run
    return o;
  };

  // Safety first: every protocol is built and checked against the limits before any byte is sent.
  double total_machine_s = 0;
  for (const auto& e : exps) total_machine_s += protocols::run_experiment(options_for(e, true)).experiment.estimated_duration_s;

  ProgressBar bar(ctx, static_cast<int>(exps.size()) + 3);
  std::map<std::string, protocols::RunResult> runs;
  for (const auto& e : exps) {
    auto o = options_for(e, false);
    const double est = protocols::run_experiment(options_for(e, true)).experiment.estimated_duration_s;
    bar.begin("run " + e.name, sim ? std::max(1.0, est / 4) : est);
    runs[e.name] = protocols::run_experiment(o);
    bar.end(runs[e.name].status);
  }

  Envelope env("calibrate");
  // Inputs are recorded relative to the run directory: the run can move, and two runs of the
  // same machine give byte-identical results.json files.
  auto add_input = [&](const std::string& path) {
    env.add_input(fs::relative(path, run_dir).generic_string(), ident::read_file_bytes(path));
  };
  env.set_options({{"machine", a.machine}, {"profile", a.profile.empty() ? "builtin" : a.profile},
                   {"firmware", a.firmware}, {"config", a.config}, {"write", a.write}, {"sim", a.sim_options}});
  nlohmann::json& res = env.results();
  nlohmann::json plot = nlohmann::json::object();
  res["machine"] = profile.name;
  nlohmann::json summary = nlohmann::json::array();
  std::vector<std::string> export_inputs;

  bar.begin("identify models", 3);
  if (runs.count("liquefier-step")) {
    const auto& r = runs["liquefier-step"];
    const std::string csv = r.files.at("load_cell");
    const std::string out = run_dir + "/analysis/step.json";
    const auto j = analyze({"step", csv, "--time", "time", "--input", "feed", "--output", "force", "--model", "fopdt"}, out, ctx);
    add_input(csv);
    res["liquefier"]["step"] = j.at("results");
    plot["step"] = step_plotdata(csv, j.at("results"));
    export_inputs.push_back(out);
    summary.push_back({{"label", "liquefier time constant tau"}, {"path", "liquefier.step.pooled.params.tau_s.value"}, {"unit", "s"}});
    summary.push_back({{"label", "tau standard error"}, {"path", "liquefier.step.pooled.params.tau_s.stderr"}, {"unit", "s"}});
    summary.push_back({{"label", "liquefier dead time theta"}, {"path", "liquefier.step.pooled.params.theta_s.value"}, {"unit", "s"}});
    summary.push_back({{"label", "liquefier gain K"}, {"path", "liquefier.step.pooled.params.K.value"}, {"unit", "N/(mm/s)"}});
  }
  if (runs.count("liquefier-chirp")) {
    const auto& r = runs["liquefier-chirp"];
    const std::string csv = r.files.at("load_cell");
    const std::string out = run_dir + "/analysis/freq.json";
    const auto j = analyze({"freq", csv, "--time", "time", "--input", "feed", "--output", "force", "--mode", "h1",
                            "--fit-tf", "1,0", "--tf-delay", "--fmax", "5"},
                           out, ctx);
    add_input(csv);
    res["liquefier"]["freq"] = j.at("results");
    plot["bode"] = bode_plotdata(j.at("results"));
    summary.push_back({{"label", "tau from the frequency response"}, {"path", "liquefier.freq.tf_fit.params.tau_s.value"}, {"unit", "s"}});
  }
  for (const char* axis : {"x", "y"}) {
    const std::string name = std::string("axis-") + axis;
    if (!runs.count(name)) continue;
    const std::string csv = runs[name].files.at("accel");
    const std::string out = run_dir + "/analysis/shaper_" + axis + ".json";
    const auto j = analyze({"shaper", csv, "--axis", axis}, out, ctx);
    add_input(csv);
    res["axes"][axis] = j.at("results").at("axes").at(axis);
    plot[std::string("psd_") + axis] = psd_plotdata(res["axes"][axis]);
    export_inputs.push_back(out);
    const std::string base = std::string("axes.") + axis;
    summary.push_back({{"label", fmt::format("{} resonance frequency", axis)}, {"path", base + ".modes[0].freq_hz"}, {"unit", "Hz"}});
    summary.push_back({{"label", fmt::format("{} damping ratio", axis)}, {"path", base + ".modes[0].zeta"}, {"unit", "1"}});
    summary.push_back({{"label", fmt::format("{} shaper frequency", axis)}, {"path", base + ".recommended.freq_hz"}, {"unit", "Hz"}});
    summary.push_back({{"label", fmt::format("{} max acceleration", axis)}, {"path", base + ".recommended.max_accel_mm_s2"}, {"unit", "mm/s^2"}});
  }
  bar.end("models identified");

  // Compensators and the configuration change (preview unless --write).
  bar.begin("design compensators", 1);
  std::string config = a.config;
  if (config.empty()) {
    const std::map<std::string, std::string> examples{
        {"klipper", "printer.cfg"}, {"marlin", "Configuration_adv.h"}, {"rrf", "config.g"}};
    const auto it = examples.find(a.firmware);
    if (it == examples.end()) throw InputError("--firmware must be klipper, marlin or rrf");
    config = run_dir + "/config/" + it->second;
    fs::copy_file(std::string(TUNEKIT_DATASETS_DIR) + "/firmware/" + it->second, config, fs::copy_options::overwrite_existing);
  }
  std::vector<std::string> export_args{"export", "--firmware", a.firmware, "--config", config, "--profile", profile_path};
  export_args.insert(export_args.end(), export_inputs.begin(), export_inputs.end());
  if (a.write) export_args.push_back("--write");
  const auto ex = analyze(export_args, run_dir + "/analysis/export.json", ctx);
  res["compensators"] = ex.at("results");
  const auto* diff_node = json_at(ex.at("results"), "export.diff");
  const std::string diff = diff_node != nullptr && diff_node->is_string() ? diff_node->get<std::string>() : std::string();
  res["config_diff"] = diff;
  protocols::write_file_atomic(run_dir + "/config/changes.diff", diff);
  if (json_at(res, "compensators.settings.pa_k_s") != nullptr && res["compensators"]["settings"]["pa_k_s"].is_number())
    summary.push_back({{"label", "pressure advance K"}, {"path", "compensators.settings.pa_k_s"}, {"unit", "s"}});
  if (json_at(res, "compensators.settings.pa_smooth_s") != nullptr &&
      res["compensators"]["settings"]["pa_smooth_s"].is_number())
    summary.push_back({{"label", "advance smoothing time"}, {"path", "compensators.settings.pa_smooth_s"}, {"unit", "s"}});
  bar.end(diff.empty() ? "configuration already up to date" : "configuration diff ready");
  res["summary"] = summary;
  for (const auto& w : ex.value("warnings", std::vector<std::string>{})) {
    nlohmann::json wj = w;
    strip_prefix(wj, run_dir + "/");
    env.warn(wj.get<std::string>());
  }

  strip_prefix(res, run_dir + "/");
  bar.begin("write report", 2);
  protocols::write_file_atomic(run_dir + "/results.json", env.dump());
  protocols::write_file_atomic(run_dir + "/plotdata.json", plot.dump() + "\n");
  const std::string report = write_report(run_dir);
  bar.end(report);

  if (!a.output.json) {
    if (!diff.empty()) ctx.out << diff << (diff.back() == '\n' ? "" : "\n");
    ctx.out << fmt::format("report: {}\n", report);
  }
  output.record_source = run_dir;
  return emit(env, output, ctx);
}

}  // namespace

void register_calibrate(CLI::App& app, CliContext& ctx) {
  auto a = std::make_shared<CalibrateArgs>();
  auto* sub = app.add_subcommand("calibrate", "Guided calibration: experiments, identification, compensators, report");
  sub->add_option("-m,--machine", a->machine, "'sim' (the built-in simulated printer) or a port (with --profile)")
      ->capture_default_str();
  sub->add_option("-p,--profile", a->profile, "Machine profile TOML: limits (mm, mm/s, mm/s^2) and sensors");
  sub->add_option("--port", a->port, "Serial device, pseudo-terminal or unix:SOCKET of a real machine");
  sub->add_option("--out", a->out_dir, "Run directory (default: runs/calibrate-UTCSTAMP)");
  sub->add_option("-f,--firmware", a->firmware, "Configuration dialect to update: klipper, marlin or rrf")->capture_default_str();
  sub->add_option("-c,--config", a->config,
                  "Firmware configuration to update (default: a copy of the bundled example in the run directory)");
  sub->add_flag("--write", a->write, "Apply the configuration change (backup + atomic replace); default: preview the diff");
  sub->add_flag("--skip-liquefier", a->skip_liquefier, "Leave out the liquefier step and chirp tests");
  sub->add_flag("--skip-axes", a->skip_axes, "Leave out the X and Y resonance sweeps");
  sub->add_option("--sim", a->sim_options, "Simulator truth and faults, KEY=VALUE (see 'tunekit run --help')");
  add_output_options(sub, a->output);
  sub->footer(
      "Examples:\n"
      "  tunekit calibrate --machine sim                      # the built-in simulated printer\n"
      "  tunekit calibrate --machine sim --firmware marlin --out runs/demo\n"
      "  tunekit calibrate --machine /dev/ttyACM0 --profile my-printer.toml --firmware marlin \\\n"
      "                    --config Marlin/Configuration_adv.h\n"
      "Every protocol is checked against the profile before anything is sent. On a terminal each step shows a\n"
      "progress bar with the time left; off a terminal only the diff and the report path are printed.");
  sub->callback([a, &ctx] { set_exit_code(run_calibrate(*a, ctx)); });
}

}  // namespace tunekit::cli
