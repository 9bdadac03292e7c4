#pragma once
// Client of Klipper's API server (klippy -a /tmp/klippy_uds): JSON objects over a Unix-domain
// socket, each terminated by the byte 0x03. Requests {"id", "method", "params"}; responses
// carry the same "id" with "result" or "error"; subscriptions (adxl345/dump_adxl345) send
// asynchronous messages without "id": the request's response_template plus "params".
// Used methods: info, gcode/script {"script"}, adxl345/dump_adxl345 {"sensor",
// "response_template"} whose messages carry params.data = [[time, ax, ay, az], ...] (mm/s^2).

#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "tunekit/machine/journal.hpp"
#include "tunekit/machine/transport.hpp"

namespace tunekit::machine {

class KlipperApiClient {
 public:
  KlipperApiClient(std::unique_ptr<Transport> t, Journal* journal);

  /// Called for every asynchronous message (no "id").
  std::function<void(const nlohmann::json&)> on_message;
  /// Called after each batch of received messages is handled.
  std::function<void()> on_batch;

  /// Sends a request and waits for its response; returns "result". An "error" response or a
  /// timeout is a MachineError.
  nlohmann::json call(const std::string& method, nlohmann::json params, std::chrono::milliseconds timeout);
  /// Handles messages arriving within `duration` (for trailing subscription data).
  void pump(std::chrono::milliseconds duration);
  Transport& transport() { return *t_; }

 private:
  void handle(const std::string& frame, long want_id, std::optional<nlohmann::json>& response);
  std::unique_ptr<Transport> t_;
  Journal* journal_;
  LineReader reader_;
  long next_id_ = 1;
};

}  // namespace tunekit::machine
