#pragma once
// Files on a RepRapFirmware board, read over its standalone web server (the "rr_" HTTP API).
//
// RepRapFirmware offers no way to read a file's contents over USB serial: of its file
// commands M28/M29 write a file, M30 deletes one, M20 lists a folder, M36 returns file
// information, M38 a file's SHA1 and M39 the card's details (src/GCodes/GCodes2.cpp, cases 20,
// 28, 29, 30, 36, 38, 39), and the expression function fileread() returns one line of
// delimited values (src/GCodes/GCodeBuffer/ExpressionParser.cpp, ReadArrayFromFile). A host
// fetches a file with GET /rr_download?name=<path> (src/Networking/HttpResponder.cpp:
// SendJsonResponse "download" -> SendFile: "HTTP/1.1 200 OK", Content-Length, the bytes;
// "HTTP/1.1 404 file not found" when it cannot be opened).
//
// Sessions (HttpResponder.cpp, GetJsonResponse "connect", CheckAuthenticated; RepRapFirmware's
// "HTTP requests" documentation): every request but rr_connect is answered "401 Not authorized"
// unless the client holds a session. A board without a password (M551; RepRap.cpp NoPasswordSet:
// none, or the default "reprap") opens one for any request. Otherwise the client logs in with
// GET /rr_connect?password=<pw>&time=<local time>&sessionKey=yes, which answers {"err":1} for a
// wrong password, {"err":2} when no session is free, and {"err":0,"sessionTimeout":..,
// "sessionKey":<n>,..} on success; the key goes back in an X-Session-Key header (versions
// before the key answer none: the session is then the client's address). rr_disconnect ends it;
// a session unused for sessionTimeout ms ends by itself. The query decodes %XX with upper-case
// hex digits only and '+' as a space, so the password is percent-encoded (url_encode).
//
// Accelerometer runs (M956, src/Accelerometers/Accelerometers.cpp): "M956 P0 S<samples> A0
// F"<name>"" records <samples> samples into 0:/sys/accelerometer/<name> in the background and
// ends the file with "Rate <Hz>, overflows <n>"; "M955 P0" reports the sampling rate
// ("Accelerometer 0 type LIS3DH with orientation 20 samples at 1344Hz with ...").

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace tunekit::machine {

struct HttpAddress {
  std::string host;
  int port = 80;
  std::string text() const;  ///< "http://host:port"
};

/// "http://HOST[:PORT]" (a trailing '/' is allowed). InputError otherwise (https is not
/// served by RepRapFirmware's standalone web server).
HttpAddress parse_http_address(const std::string& url);

struct HttpReply {
  int status = 0;
  std::string reason;
  std::string body;
};

/// One GET over HTTP/1.1 (Connection: close); `extra_headers` are whole header lines, each ending
/// in "\r\n". MachineError when the host cannot be reached, the reply is not HTTP, or nothing
/// arrives within `timeout`; its text shows a password in the query as "***".
HttpReply http_get(const HttpAddress& to, const std::string& path_and_query, std::chrono::milliseconds timeout,
                   const std::string& extra_headers = {});

/// Percent-encodes a query value (RFC 3986 unreserved characters pass).
std::string url_encode(std::string_view v);

/// The environment variable that gives RepRapFirmware's web server password (M551), so that it
/// need not be written on a command line or in a profile.
inline constexpr const char* kRrfPasswordEnv = "TUNEKIT_RRF_PASSWORD";

/// The password to log in with: kRrfPasswordEnv when set and not empty, else `configured` (the
/// profile's [network] password) when not empty, else nullopt (none given).
std::optional<std::string> rrf_password(const std::string& configured);

/// A session on the board's web server: where, and the key RepRapFirmware answered (0: none,
/// the session is the client's address).
struct RrfSession {
  HttpAddress to;
  std::uint32_t key = 0;
};

/// Logs in (rr_connect). Without a password it offers RepRapFirmware's default, "reprap", which
/// a board without M551 accepts. MachineError (exit 3), never showing the password: {"err":1}
/// "RepRapFirmware refused the password" (or, none given, that the board needs one), {"err":2}
/// no free session, and any other answer.
RrfSession rrf_connect(const HttpAddress& to, const std::optional<std::string>& password,
                       std::chrono::milliseconds timeout);

/// Ends a session (rr_disconnect); best effort, never throws.
void rrf_disconnect(const RrfSession& s, std::chrono::milliseconds timeout) noexcept;

/// A session for the lifetime of the object: rr_connect on construction, rr_disconnect after.
class RrfLogin {
 public:
  RrfLogin(const HttpAddress& to, const std::optional<std::string>& password, std::chrono::milliseconds timeout)
      : session_(rrf_connect(to, password, timeout)), timeout_(timeout) {}
  ~RrfLogin() { rrf_disconnect(session_, timeout_); }
  RrfLogin(const RrfLogin&) = delete;
  RrfLogin& operator=(const RrfLogin&) = delete;
  const RrfSession& session() const { return session_; }

 private:
  RrfSession session_;
  std::chrono::milliseconds timeout_;
};

/// The bytes of `name` (e.g. "0:/sys/accelerometer/x.csv") through rr_download, within the
/// session. MachineError with the status for anything but 200.
std::string rrf_download(const RrfSession& s, const std::string& name, std::chrono::milliseconds timeout);
/// The same without logging in (a board without a password).
std::string rrf_download(const HttpAddress& to, const std::string& name, std::chrono::milliseconds timeout);

/// The sampling rate (Hz) in RepRapFirmware's M955 report, nullopt if the lines have none.
std::optional<double> parse_m955_rate_hz(const std::vector<std::string>& lines);

/// True when an M956 file is finished: its last line is the "Rate ..." trailer or one of the
/// failure lines RepRapFirmware writes instead.
bool rrf_accelerometer_file_complete(std::string_view bytes);

}  // namespace tunekit::machine
