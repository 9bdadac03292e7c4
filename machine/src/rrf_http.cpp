#include "tunekit/machine/rrf_http.hpp"

#include <netdb.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <ctime>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "tunekit/core/error.hpp"

namespace tunekit::machine {
namespace {

/// A connected TCP socket, closed on destruction.
class HttpSocket {
 public:
  explicit HttpSocket(int fd) : fd_(fd) {}
  ~HttpSocket() {
    if (fd_ >= 0) ::close(fd_);
  }
  HttpSocket(const HttpSocket&) = delete;
  HttpSocket& operator=(const HttpSocket&) = delete;
  int fd() const { return fd_; }

 private:
  int fd_;
};

int http_connect(const HttpAddress& to) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* res = nullptr;
  const std::string port = std::to_string(to.port);
  if (const int rc = ::getaddrinfo(to.host.c_str(), port.c_str(), &hints, &res); rc != 0)
    throw MachineError(fmt::format("cannot resolve '{}': {}", to.host, ::gai_strerror(rc)), to.text());
  int fd = -1;
  int err = 0;
  for (addrinfo* a = res; a != nullptr; a = a->ai_next) {
    fd = ::socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC, a->ai_protocol);
    if (fd < 0) {
      err = errno;
      continue;
    }
    if (::connect(fd, a->ai_addr, a->ai_addrlen) == 0) break;
    err = errno;
    ::close(fd);
    fd = -1;
  }
  ::freeaddrinfo(res);
  if (fd < 0) throw MachineError(fmt::format("cannot connect: {}", std::strerror(err)), to.text());
  return fd;
}

/// The request target as messages show it: a password's value replaced by "***".
std::string shown_target(const std::string& path_and_query) {
  std::string s = path_and_query;
  for (auto p = s.find("password="); p != std::string::npos; p = s.find("password=", p + 1)) {
    const auto b = p + 9, e = std::min(s.find('&', b), s.size());
    s.replace(b, e - b, "***");
  }
  return s;
}

/// The local time as rr_connect's "time" takes it (HttpResponder.cpp: "%Y-%m-%dT%H:%M:%S").
std::string rrf_local_time() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  ::localtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%S", &tm);
  return buf;
}

/// The X-Session-Key header line of a session with a key.
std::string session_header(const RrfSession& s) {
  return s.key == 0 ? std::string() : fmt::format("X-Session-Key: {}\r\n", s.key);
}

}  // namespace

std::string HttpAddress::text() const { return fmt::format("http://{}:{}", host, port); }

HttpAddress parse_http_address(const std::string& url) {
  const std::string scheme = "http://";
  if (url.rfind(scheme, 0) != 0)
    throw InputError(fmt::format("network address '{}' must start with http:// (RepRapFirmware's web server)", url));
  std::string rest = url.substr(scheme.size());
  while (!rest.empty() && rest.back() == '/') rest.pop_back();
  if (rest.empty() || rest.find('/') != std::string::npos)
    throw InputError(fmt::format("network address '{}' must be http://HOST[:PORT]", url));
  HttpAddress a;
  const auto colon = rest.rfind(':');
  if (colon != std::string::npos && rest.find(']') == std::string::npos) {
    const std::string p = rest.substr(colon + 1);
    char* end = nullptr;
    const long v = std::strtol(p.c_str(), &end, 10);
    if (p.empty() || *end != '\0' || v < 1 || v > 65535)
      throw InputError(fmt::format("network address '{}': port must be 1 to 65535", url));
    a.port = static_cast<int>(v);
    rest = rest.substr(0, colon);
  }
  a.host = rest;
  return a;
}

std::string url_encode(std::string_view v) {
  std::string out;
  for (unsigned char c : v) {
    if (std::isalnum(c) || c == '-' || c == '_' || c == '.' || c == '~') out.push_back(static_cast<char>(c));
    else out += fmt::format("%{:02X}", c);
  }
  return out;
}

HttpReply http_get(const HttpAddress& to, const std::string& path_and_query, std::chrono::milliseconds timeout,
                   const std::string& extra_headers) {
  HttpSocket sock(http_connect(to));
  const std::string req =
      fmt::format("GET {} HTTP/1.1\r\nHost: {}\r\n{}Connection: close\r\n\r\n", path_and_query, to.host, extra_headers);
  for (std::size_t sent = 0; sent < req.size();) {
    const ssize_t n = ::send(sock.fd(), req.data() + sent, req.size() - sent, MSG_NOSIGNAL);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw MachineError(fmt::format("sending the request failed: {}", std::strerror(errno)), to.text());
    }
    sent += static_cast<std::size_t>(n);
  }
  std::string data;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  std::size_t header_end = std::string::npos;
  long content_length = -1;
  for (;;) {
    if (header_end != std::string::npos && content_length >= 0 &&
        data.size() >= header_end + 4 + static_cast<std::size_t>(content_length))
      break;
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0)
      throw MachineError(
          fmt::format("no complete reply to GET {} within {} ms", shown_target(path_and_query), timeout.count()),
          to.text());
    pollfd p{sock.fd(), POLLIN, 0};
    const int pr = ::poll(&p, 1, static_cast<int>(left.count()));
    if (pr < 0 && errno == EINTR) continue;
    if (pr <= 0) continue;
    char buf[16384];
    const ssize_t n = ::recv(sock.fd(), buf, sizeof buf, 0);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw MachineError(fmt::format("reading the reply failed: {}", std::strerror(errno)), to.text());
    }
    if (n == 0) break;  // Connection: close
    data.append(buf, static_cast<std::size_t>(n));
    if (header_end == std::string::npos) {
      header_end = data.find("\r\n\r\n");
      if (header_end != std::string::npos) {
        std::string head = data.substr(0, header_end);
        for (auto& c : head) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
        const auto cl = head.find("\r\ncontent-length:");
        if (cl != std::string::npos) content_length = std::strtol(head.c_str() + cl + 17, nullptr, 10);
      }
    }
  }
  if (data.rfind("HTTP/1.", 0) != 0 || header_end == std::string::npos)
    throw MachineError(fmt::format("the reply to GET {} is not HTTP", shown_target(path_and_query)), to.text());
  HttpReply r;
  const auto eol = data.find("\r\n");
  const std::string status_line = data.substr(0, eol);
  const auto sp = status_line.find(' ');
  r.status = sp == std::string::npos ? 0 : std::atoi(status_line.c_str() + sp + 1);
  const auto sp2 = status_line.find(' ', sp + 1);
  r.reason = sp2 == std::string::npos ? std::string() : status_line.substr(sp2 + 1);
  r.body = data.substr(header_end + 4);
  if (content_length >= 0 && r.body.size() > static_cast<std::size_t>(content_length))
    r.body.resize(static_cast<std::size_t>(content_length));
  return r;
}

std::optional<std::string> rrf_password(const std::string& configured) {
  if (const char* env = std::getenv(kRrfPasswordEnv); env != nullptr && *env != '\0') return std::string(env);
  if (!configured.empty()) return configured;
  return std::nullopt;
}

RrfSession rrf_connect(const HttpAddress& to, const std::optional<std::string>& password,
                       std::chrono::milliseconds timeout) {
  // RepRapFirmware's default password: a board without M551 accepts it (RepRap.cpp NoPasswordSet).
  const std::string pw = password.value_or("reprap");
  const auto r = http_get(
      to, fmt::format("/rr_connect?password={}&time={}&sessionKey=yes", url_encode(pw), url_encode(rrf_local_time())),
      timeout);
  if (r.status != 200)
    throw MachineError(fmt::format("RepRapFirmware's web server answered rr_connect with {} {}", r.status, r.reason),
                       to.text());
  const auto j = nlohmann::json::parse(r.body, nullptr, false);
  const int err = j.is_object() && j.contains("err") && j["err"].is_number_integer() ? j["err"].get<int>() : -1;
  if (err == 1 && password)
    throw MachineError(fmt::format("RepRapFirmware refused the password (check {} or the profile's [network] password)",
                                   kRrfPasswordEnv),
                       to.text());
  if (err == 1)
    throw MachineError(fmt::format("RepRapFirmware's web server is protected by a password (M551) and none was given: "
                                   "set {} or the profile's [network] password",
                                   kRrfPasswordEnv),
                       to.text());
  if (err == 2)
    throw MachineError("RepRapFirmware has no HTTP session free (too many clients connected); close one and retry",
                       to.text());
  if (err != 0) throw MachineError("RepRapFirmware's answer to rr_connect is not {\"err\":0,...}", to.text());
  RrfSession s{to, 0};
  if (j.contains("sessionKey") && j["sessionKey"].is_number_unsigned()) s.key = j["sessionKey"].get<std::uint32_t>();
  return s;
}

void rrf_disconnect(const RrfSession& s, std::chrono::milliseconds timeout) noexcept {
  try {
    (void)http_get(s.to, "/rr_disconnect", timeout, session_header(s));
  } catch (...) {  // the session ends by itself after its timeout
  }
}

std::string rrf_download(const RrfSession& s, const std::string& name, std::chrono::milliseconds timeout) {
  const auto r = http_get(s.to, "/rr_download?name=" + url_encode(name), timeout, session_header(s));
  if (r.status != 200)
    throw MachineError(fmt::format("rr_download of '{}' answered {} {}", name, r.status, r.reason), s.to.text());
  return r.body;
}

std::string rrf_download(const HttpAddress& to, const std::string& name, std::chrono::milliseconds timeout) {
  return rrf_download(RrfSession{to, 0}, name, timeout);
}

std::optional<double> parse_m955_rate_hz(const std::vector<std::string>& lines) {
  for (const auto& l : lines) {
    const auto p = l.find(" samples at ");
    if (p == std::string::npos) continue;
    char* end = nullptr;
    const double v = std::strtod(l.c_str() + p + 12, &end);
    if (end != l.c_str() + p + 12 && v > 0 && std::string_view(end).rfind("Hz", 0) == 0) return v;
  }
  return std::nullopt;
}

bool rrf_accelerometer_file_complete(std::string_view bytes) {
  while (!bytes.empty() && (bytes.back() == '\n' || bytes.back() == '\r')) bytes.remove_suffix(1);
  const auto nl = bytes.rfind('\n');
  const std::string_view last = nl == std::string_view::npos ? bytes : bytes.substr(nl + 1);
  // Accelerometers.cpp: the trailer "Rate %u, overflows %u", or a failure line.
  return last.rfind("Rate ", 0) == 0 || last.rfind("Failed to", 0) == 0 || last.rfind("Received bad data", 0) == 0 ||
         last.rfind("Received mismatched data", 0) == 0;
}

}  // namespace tunekit::machine
