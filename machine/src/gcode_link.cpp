#include "tunekit/machine/gcode_link.hpp"

#include <cctype>
#include <cstdlib>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/machine/gcode.hpp"

namespace tunekit::machine {
namespace {

bool starts_with(std::string_view s, std::string_view p) { return s.substr(0, p.size()) == p; }

bool is_ok(std::string_view l) { return l == "ok" || starts_with(l, "ok ") || starts_with(l, "ok\t"); }

std::optional<long> resend_number(std::string_view l) {
  std::string_view rest;
  if (starts_with(l, "Resend:")) rest = l.substr(7);
  else if (starts_with(l, "rs ")) rest = l.substr(3);
  else return std::nullopt;
  while (!rest.empty() && !std::isdigit(static_cast<unsigned char>(rest.front()))) rest.remove_prefix(1);
  if (rest.empty()) return -1;
  return std::strtol(std::string(rest).c_str(), nullptr, 10);
}

bool recoverable_error(std::string_view l) {
  return l.find("checksum") != std::string_view::npos || l.find("Checksum") != std::string_view::npos ||
         l.find("Line Number") != std::string_view::npos ||
         l.find("No firmware::Line Number") != std::string_view::npos;
}

}  // namespace

GcodeLink::GcodeLink(Transport& t, Journal* journal, LinkOptions options)
    : t_(t), journal_(journal), opt_(options), reader_(t) {}

void GcodeLink::write_numbered(long n) {
  const std::string& cmd = history_.at(n);
  const std::string wire = opt_.line_numbers ? numbered_line(n, cmd) : cmd;
  if (journal_) journal_->sent(wire);
  t_.write(wire + "\n");
  ++stats_.lines_sent;
}

void GcodeLink::reset_line_numbers() {
  // "N0 M110 N0*cs": the firmware's last line number becomes 0, the next line is N1.
  line_no_ = -1;
  history_.clear();
  if (opt_.line_numbers) send("M110 N0");
}

void GcodeLink::check_abort() const {
  if (abort_flag && abort_flag->load()) throw MachineError("interrupted", t_.describe());
}

void GcodeLink::write_checked(const std::string& command) {
  if (guard)
    if (const auto why = guard->refuse(command)) {
      if (journal_) journal_->error("refused to send a line", {{"line", command}, {"reason", *why}});
      throw MachineError(fmt::format("refused to send '{}': {} (nothing of it was sent)", command, *why),
                         t_.describe());
    }
  const long n = ++line_no_;
  history_[n] = command;
  if (history_.size() > 64) history_.erase(history_.begin());
  write_numbered(n);
}

std::vector<std::string> GcodeLink::send(const std::string& command) {
  write_checked(command);
  const long n = line_no_;
  std::vector<std::string> info;
  long resend_pending = -1;  // line the firmware asked for, sent after the next ok
  int retries = 0;
  auto last_activity = std::chrono::steady_clock::now();
  for (;;) {
    check_abort();
    const auto silent = std::chrono::steady_clock::now() - last_activity;
    if (silent >= opt_.timeout) {
      if (++retries > opt_.max_retries)
        throw MachineError(fmt::format("no answer to line {} ('{}') after {} retries of {} ms", n, command,
                                       opt_.max_retries, opt_.timeout.count()),
                           t_.describe());
      ++stats_.retries;
      if (journal_) journal_->event("timeout: sending the line again", {{"line_number", n}, {"retry", retries}});
      write_numbered(n);
      last_activity = std::chrono::steady_clock::now();
      continue;
    }
    const auto wait = std::min<std::chrono::milliseconds>(
        std::chrono::duration_cast<std::chrono::milliseconds>(opt_.timeout - silent) + std::chrono::milliseconds(1),
        std::chrono::milliseconds(200));
    auto line = reader_.next(wait);
    if (!line) continue;
    last_activity = std::chrono::steady_clock::now();
    std::string_view l = *line;
    if (is_ok(l)) {
      if (journal_) journal_->received(l);
      if (on_batch) on_batch();
      if (resend_pending >= 0) {
        const long r = resend_pending;
        resend_pending = -1;
        ++stats_.resends;
        write_numbered(r);
        continue;
      }
      return info;
    }
    if (const auto r = resend_number(l)) {
      if (journal_) journal_->received(l);
      if (!history_.count(*r) || *r != n)
        throw MachineError(fmt::format("the firmware asked to resend line {}, but line {} is the one in flight", *r, n),
                           t_.describe());
      resend_pending = *r;
      continue;
    }
    if (starts_with(l, "Error:") || starts_with(l, "error:") || starts_with(l, "!!")) {
      if (journal_) journal_->received(l);
      if (starts_with(l, "!!") || !recoverable_error(l))
        throw MachineError(fmt::format("firmware error after '{}': {}", command, l), t_.describe());
      continue;
    }
    if (starts_with(l, "busy:") || starts_with(l, "echo:busy:")) {
      ++stats_.busy;
      if (journal_) journal_->received(l);
      continue;
    }
    if (on_line && on_line(l)) {
      // Sensor data reach the run directory every 64 lines and at every "ok".
      if (++stats_.data_lines % 64 == 0 && on_batch) on_batch();
      continue;
    }
    if (journal_) journal_->received(l);
    info.emplace_back(l);
  }
}

void GcodeLink::send_pipelined(const std::vector<std::string>& commands, std::size_t window) {
  if (window <= 1) {
    for (const auto& c : commands) {
      check_abort();
      send(c);
    }
    return;
  }
  std::size_t written = 0, answered = 0;
  auto last_activity = std::chrono::steady_clock::now();
  while (answered < commands.size()) {
    check_abort();
    for (; written < commands.size() && written - answered < window; ++written) write_checked(commands[written]);
    const auto silent = std::chrono::steady_clock::now() - last_activity;
    if (silent >= opt_.timeout)
      throw MachineError(fmt::format("no answer to '{}' for {} ms with {} lines sent ahead (not sent again)",
                                     commands[answered], opt_.timeout.count(), written - answered),
                         t_.describe());
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(opt_.timeout - silent);
    auto line = reader_.next(
        std::min<std::chrono::milliseconds>(left + std::chrono::milliseconds(1), std::chrono::milliseconds(200)));
    if (!line) continue;
    last_activity = std::chrono::steady_clock::now();
    const std::string_view l = *line;
    if (is_ok(l)) {
      if (journal_) journal_->received(l);
      ++answered;
      if (on_batch) on_batch();
    } else if (resend_number(l) || starts_with(l, "Error:") || starts_with(l, "error:") || starts_with(l, "!!")) {
      if (journal_) journal_->received(l);
      throw MachineError(fmt::format("firmware answer after '{}' with lines sent ahead: {}", commands[answered], l),
                         t_.describe());
    } else if (on_line && on_line(l)) {
      if (++stats_.data_lines % 64 == 0 && on_batch) on_batch();
    } else {
      if (starts_with(l, "busy:") || starts_with(l, "echo:busy:")) ++stats_.busy;
      if (journal_) journal_->received(l);
    }
  }
}

void GcodeLink::send_best_effort(const std::vector<std::string>& commands, std::chrono::milliseconds wait) {
  try {
    for (const auto& c : commands) {
      if (journal_) journal_->sent(c);
      t_.write(c + "\n");
    }
    const auto deadline = std::chrono::steady_clock::now() + wait;
    while (std::chrono::steady_clock::now() < deadline) {
      auto l = reader_.next(std::chrono::milliseconds(20));
      if (!l) continue;
      if (on_line && on_line(*l)) continue;
      if (journal_) journal_->received(*l);
    }
  } catch (const std::exception& e) {
    if (journal_) journal_->error("safe-state commands could not be delivered", {{"reason", e.what()}});
  }
}

}  // namespace tunekit::machine
