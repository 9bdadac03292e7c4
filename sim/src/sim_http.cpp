// The simulated RepRapFirmware board's web server (simulator.hpp SimHttpServer), answering
// rr_download as RepRapFirmware's src/Networking/HttpResponder.cpp does.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
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
    std::string reply;
    const auto sp1 = req.find(' '), sp2 = req.find(' ', sp1 == std::string::npos ? 0 : sp1 + 1);
    const std::string method = sp1 == std::string::npos ? std::string() : req.substr(0, sp1);
    const std::string target = sp2 == std::string::npos ? std::string() : req.substr(sp1 + 1, sp2 - sp1 - 1);
    const std::string prefix = "/rr_download?name=";
    if (method != "GET") {
      reply = sim_http_reject("only rr_upload is supported for POST requests", 500);
    } else if (target.rfind(prefix, 0) == 0) {
      std::string name = sim_http_url_decode(target.substr(prefix.size()));
      if (const auto amp = name.find('&'); amp != std::string::npos) name.resize(amp);
      if (const auto body = sim_.file(name)) {
        reply = fmt::format(
            "HTTP/1.1 200 OK\r\nCache-Control: no-cache, no-store, must-revalidate\r\nPragma: no-cache\r\nExpires: "
            "0\r\nAccess-Control-Allow-Origin: *\r\nContent-Type: application/octet-stream\r\nContent-Length: {}\r\n"
            "Connection: close\r\n\r\n",
            body->size());
        reply += *body;
      } else {
        reply = sim_http_reject("file not found", 404);
      }
    } else {
      reply = sim_http_reject("page not found", 404);
    }
    sim_http_send_all(fd, reply);
    ::close(fd);
  }
}

}  // namespace tunekit::sim
