// The simulated RepRapFirmware board's web server (simulator.hpp SimHttpServer), answering
// rr_connect, rr_disconnect and rr_download, with its sessions, as RepRapFirmware's
// src/Networking/HttpResponder.cpp does.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <map>
#include <string>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/sim/simulator.hpp"

namespace tunekit::sim {
namespace {

std::string sim_http_url_decode(std::string_view v) {
  std::string out;
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (v[i] == '%' && i + 2 < v.size() && std::isxdigit(static_cast<unsigned char>(v[i + 1])) &&
        std::isxdigit(static_cast<unsigned char>(v[i + 2]))) {
      out.push_back(static_cast<char>(std::stoi(std::string(v.substr(i + 1, 2)), nullptr, 16)));
      i += 2;
    } else {
      out.push_back(v[i] == '+' ? ' ' : v[i]);
    }
  }
  return out;
}

void sim_http_send_all(int fd, const std::string& s) {
  for (std::size_t sent = 0; sent < s.size();) {
    const ssize_t n = ::send(fd, s.data() + sent, s.size() - sent, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return;
    sent += static_cast<std::size_t>(n);
  }
}

/// HttpResponder.cpp RejectMessage: "HTTP/1.1 %u %s\r\nConnection: close\r\n" ... then a page.
std::string sim_http_reject(const std::string& response, int code) {
  return fmt::format("HTTP/1.1 {} {}\r\nConnection: close\r\n\r\n<html><body>{}</body></html>", code, response,
                     response);
}

/// A 200 reply with a body (HttpResponder.cpp's JSON replies and SendFile).
std::string sim_http_ok(const std::string& type, const std::string& body) {
  return fmt::format(
      "HTTP/1.1 200 OK\r\nCache-Control: no-cache, no-store, must-revalidate\r\nPragma: no-cache\r\nExpires: "
      "0\r\nContent-Type: {}\r\nContent-Length: {}\r\nConnection: close\r\n\r\n{}",
      type, body.size(), body);
}

/// The query's key/value pairs, decoded ('&' separates, '=' splits at its first).
std::map<std::string, std::string> sim_http_query(const std::string& target) {
  std::map<std::string, std::string> q;
  const auto mark = target.find('?');
  if (mark == std::string::npos) return q;
  std::string_view rest(target);
  rest.remove_prefix(mark + 1);
  while (!rest.empty()) {
    const auto amp = rest.find('&');
    const std::string_view kv = rest.substr(0, amp);
    const auto eq = kv.find('=');
    q[std::string(kv.substr(0, eq))] =
        eq == std::string_view::npos ? std::string() : sim_http_url_decode(kv.substr(eq + 1));
    rest = amp == std::string_view::npos ? std::string_view() : rest.substr(amp + 1);
  }
  return q;
}

/// HttpResponder.cpp GetSessionKey: the X-Session-Key header's number, 0 without one.
std::uint32_t sim_http_session_key(const std::string& request) {
  std::string lower = request;
  for (auto& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  const auto p = lower.find("\r\nx-session-key:");
  return p == std::string::npos ? 0 : static_cast<std::uint32_t>(std::strtoul(request.c_str() + p + 17, nullptr, 10));
}

}  // namespace

SimHttpServer::SimHttpServer(const Simulator& sim) : sim_(sim) {
  listen_fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (listen_fd_ < 0) throw MachineError("cannot create the simulated board's web server socket");
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = 0;
  socklen_t len = sizeof a;
  if (::bind(listen_fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 || ::listen(listen_fd_, 8) != 0 ||
      ::getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&a), &len) != 0) {
    ::close(listen_fd_);
    throw MachineError("cannot start the simulated board's web server on 127.0.0.1");
  }
  port_ = ntohs(a.sin_port);
  thread_ = std::thread([this] { serve(); });
}

SimHttpServer::~SimHttpServer() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
  if (listen_fd_ >= 0) ::close(listen_fd_);
}

std::string SimHttpServer::url() const { return fmt::format("http://127.0.0.1:{}", port_); }

void SimHttpServer::serve() {
  while (!stop_.load()) {
    pollfd p{listen_fd_, POLLIN, 0};
    if (::poll(&p, 1, 50) <= 0) continue;
    const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);
    if (fd < 0) continue;
    std::string req;
    char buf[4096];
    while (req.find("\r\n\r\n") == std::string::npos && req.size() < 65536) {
      pollfd q{fd, POLLIN, 0};
      if (::poll(&q, 1, 2000) <= 0) break;
      const ssize_t n = ::recv(fd, buf, sizeof buf, 0);
      if (n <= 0) break;
      req.append(buf, static_cast<std::size_t>(n));
    }
    ++requests_;
    const auto sp1 = req.find(' '), sp2 = req.find(' ', sp1 == std::string::npos ? 0 : sp1 + 1);
    const std::string method = sp1 == std::string::npos ? std::string() : req.substr(0, sp1);
    const std::string target = sp2 == std::string::npos ? std::string() : req.substr(sp1 + 1, sp2 - sp1 - 1);
    {
      const std::lock_guard<std::mutex> lock(targets_mu_);
      targets_.push_back(target);
    }
    const std::string reply =
        method != "GET" ? sim_http_reject("only rr_upload is supported for POST requests", 500) : answer(target, req);
    sim_http_send_all(fd, reply);
    ::close(fd);
  }
}

std::vector<std::string> SimHttpServer::targets() const {
  const std::lock_guard<std::mutex> lock(targets_mu_);
  return targets_;
}

std::string SimHttpServer::connect(const std::map<std::string, std::string>& query) {
  const std::string& board = sim_.config().rrf_password;
  const bool protected_board = !board.empty() && board != "reprap";  // RepRap.cpp NoPasswordSet
  if (protected_board && query.at("password") != board) return sim_http_ok("application/json", "{\"err\":1}");
  if (static_cast<int>(sessions_.size()) >= sim_.config().rrf_http_sessions)
    return sim_http_ok("application/json", "{\"err\":2}");
  const auto want_key = query.find("sessionKey");
  const std::uint32_t key = want_key != query.end() && want_key->second == "yes" ? next_key_++ : 0;
  sessions_.insert(key);
  return sim_http_ok("application/json",
                     fmt::format("{{\"err\":0,\"sessionTimeout\":8000,\"boardType\":\"tunekit-sim\",\"apiLevel\":1,"
                                 "\"sessionKey\":{}}}",
                                 key));
}

std::string SimHttpServer::answer(const std::string& target, const std::string& request) {
  const std::string path = target.substr(0, target.find('?'));
  const auto query = sim_http_query(target);
  const std::uint32_t key = sim_http_session_key(request);
  const std::string& board = sim_.config().rrf_password;
  // SendJsonResponse: without a password any request but rr_connect opens an address session.
  if (path != "/rr_connect" && !sessions_.count(key) && (board.empty() || board == "reprap") &&
      static_cast<int>(sessions_.size()) < sim_.config().rrf_http_sessions)
    sessions_.insert(0);
  if (path == "/rr_connect" && query.count("password")) return connect(query);
  if (!sessions_.count(key)) return sim_http_reject("Not authorized", 401);
  if (path == "/rr_disconnect") {
    sessions_.erase(key);
    return sim_http_ok("application/json", "{\"err\":0}");
  }
  if (path != "/rr_download" || !query.count("name")) return sim_http_reject("page not found", 404);
  const auto body = sim_.file(query.at("name"));
  return body ? sim_http_ok("application/octet-stream", *body) : sim_http_reject("file not found", 404);
}

}  // namespace tunekit::sim
