#include "tunekit/protocols/stop_signals.hpp"

#include <csignal>
#include <mutex>

#include "tunekit/core/error.hpp"

namespace tunekit::protocols {
namespace {

constexpr int kSignals[] = {SIGINT, SIGTERM, SIGHUP};

std::atomic<bool> g_stop{false};
std::atomic<int> g_signal{0};
std::atomic<bool> g_reported{false};  // an InterruptedError said so: the signal was handled
std::mutex g_mu;
int g_depth = 0;
struct sigaction g_old[3];

extern "C" void on_stop_signal(int sig) {
  g_signal = sig;
  g_stop = true;
}

}  // namespace

StopSignals::StopSignals() {
  std::lock_guard<std::mutex> lock(g_mu);
  if (g_depth++ > 0) return;
  g_stop = false;
  g_signal = 0;
  g_reported = false;
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;  // no SA_RESTART: a blocking wait returns EINTR and the flag is seen at once
  for (int i = 0; i < 3; ++i) {
    ::sigaction(kSignals[i], nullptr, &g_old[i]);
    // An ignored hang-up stays ignored: under nohup(1) it must not stop the run. SIGINT and
    // SIGTERM always stop it (a shell starts background jobs with SIGINT ignored, yet
    // `kill -INT` is how a script stops one).
    if (kSignals[i] != SIGHUP || g_old[i].sa_handler != SIG_IGN) ::sigaction(kSignals[i], &sa, nullptr);
  }
}

StopSignals::~StopSignals() {
  std::lock_guard<std::mutex> lock(g_mu);
  if (--g_depth > 0) return;
  for (int i = 0; i < 3; ++i) ::sigaction(kSignals[i], &g_old[i], nullptr);
  // A signal that arrived after the command's last check was never reported: the process ends
  // by it, as it would have without the guard, never with exit code 0.
  if (g_stop.load() && !g_reported.load() && g_signal.load() != 0) {
    ::signal(g_signal.load(), SIG_DFL);
    ::raise(g_signal.load());
  }
}

const std::atomic<bool>& StopSignals::flag() { return g_stop; }

std::string StopSignals::received() {
  switch (g_signal.load()) {
    case SIGINT: return "SIGINT";
    case SIGTERM: return "SIGTERM";
    case SIGHUP: return "SIGHUP";
    default: return {};
  }
}

int StopSignals::received_number() { return g_signal.load(); }

void StopSignals::throw_if_stopped(const std::string& where) {
  if (!g_stop.load() || g_signal.load() == 0) return;
  report();
  throw InterruptedError(g_signal.load(), "interrupted by " + received() + " " + where);
}

void StopSignals::report() { g_reported = true; }

}  // namespace tunekit::protocols
