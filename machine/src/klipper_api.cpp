#include "tunekit/machine/klipper_api.hpp"

#include <fmt/format.h>

#include "tunekit/core/json_error_text.hpp"
#include "tunekit/core/error.hpp"

namespace tunekit::machine {

KlipperApiClient::KlipperApiClient(std::unique_ptr<Transport> t, Journal* journal)
    : t_(std::move(t)), journal_(journal), reader_(*t_, '\x03') {}

void KlipperApiClient::handle(const std::string& frame, long want_id, std::optional<nlohmann::json>& response) {
  nlohmann::json msg;
  try {
    msg = nlohmann::json::parse(frame);
  } catch (const nlohmann::json::parse_error& e) {
    throw MachineError(fmt::format("the API server sent malformed JSON: {}", core::plain_json_error(e.what())),
                       t_->describe());
  }
  if (msg.contains("id")) {
    if (journal_) journal_->received(frame);
    if (msg["id"].is_number_integer() && msg["id"].get<long>() == want_id) response = std::move(msg);
    return;
  }
  if (on_message) on_message(msg);
}

nlohmann::json KlipperApiClient::call(const std::string& method, nlohmann::json params,
                                      std::chrono::milliseconds timeout) {
  const long id = next_id_++;
  nlohmann::json req{{"id", id}, {"method", method}, {"params", std::move(params)}};
  const std::string text = req.dump();
  if (journal_) journal_->sent(text);
  t_->write(text + "\x03");
  std::optional<nlohmann::json> response;
  auto last = std::chrono::steady_clock::now();
  while (!response) {
    auto frame = reader_.next(std::chrono::milliseconds(100));
    if (!frame) {
      if (std::chrono::steady_clock::now() - last > timeout)
        throw MachineError(fmt::format("no answer from the API server to {} within {} ms", method, timeout.count()),
                           t_->describe());
      continue;
    }
    last = std::chrono::steady_clock::now();
    handle(*frame, id, response);
    if (on_batch) on_batch();
  }
  if (response->contains("error")) {
    const auto& e = (*response)["error"];
    throw MachineError(fmt::format("Klipper refused {}: {}", method,
                                   e.is_object() && e.contains("message") ? e["message"].dump() : e.dump()),
                       t_->describe());
  }
  return response->value("result", nlohmann::json::object());
}

void KlipperApiClient::pump(std::chrono::milliseconds duration) {
  const auto deadline = std::chrono::steady_clock::now() + duration;
  std::optional<nlohmann::json> none;
  while (std::chrono::steady_clock::now() < deadline) {
    auto frame = reader_.next(std::chrono::milliseconds(20));
    if (!frame) continue;
    handle(*frame, -1, none);
    if (on_batch) on_batch();
  }
}

}  // namespace tunekit::machine
