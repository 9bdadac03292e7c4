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
// "HTTP/1.1 404 file not found" when it cannot be opened). Without a password the request is
// authorised automatically (SendJsonResponse: NoPasswordSet()).
//
// Accelerometer runs (M956, src/Accelerometers/Accelerometers.cpp): "M956 P0 S<samples> A0
// F"<name>"" records <samples> samples into 0:/sys/accelerometer/<name> in the background and
// ends the file with "Rate <Hz>, overflows <n>"; "M955 P0" reports the sampling rate
// ("Accelerometer 0 type LIS3DH with orientation 20 samples at 1344Hz with ...").

#include <chrono>
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

/// One GET over HTTP/1.1 (Connection: close). MachineError when the host cannot be reached,
/// the reply is not HTTP, or nothing arrives within `timeout`.
HttpReply http_get(const HttpAddress& to, const std::string& path_and_query, std::chrono::milliseconds timeout);

/// Percent-encodes a query value (RFC 3986 unreserved characters pass).
std::string url_encode(std::string_view v);

/// The bytes of `name` (e.g. "0:/sys/accelerometer/x.csv") through rr_download. MachineError
/// with the status for anything but 200.
std::string rrf_download(const HttpAddress& to, const std::string& name, std::chrono::milliseconds timeout);

/// The sampling rate (Hz) in RepRapFirmware's M955 report, nullopt if the lines have none.
std::optional<double> parse_m955_rate_hz(const std::vector<std::string>& lines);

/// True when an M956 file is finished: its last line is the "Rate ..." trailer or one of the
/// failure lines RepRapFirmware writes instead.
bool rrf_accelerometer_file_complete(std::string_view bytes);

}  // namespace tunekit::machine
