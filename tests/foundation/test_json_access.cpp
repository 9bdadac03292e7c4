// One JSON access: exact paths through nlohmann's json_pointer, dotted results paths converted
// to pointers, the --require path rule, and JSON files read with a located error.
#include <catch2/catch.hpp>

#include <nlohmann/json.hpp>

#include "test_support.hpp"
#include "tunekit/calibration/results/json_access.hpp"
#include "tunekit/calibration/results/requirements.hpp"
#include "tunekit/calibration/results/results_json.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/core/json_error_text.hpp"

using namespace tunekit::calibration;
using Pointer = nlohmann::json::json_pointer;

namespace {
const nlohmann::json kDoc = nlohmann::json::parse(R"({
  "axes": {"x": {"modes": [{"freq_hz": 44.2}, {"freq_hz": 61.0}]}},
  "a/b": {"c~d": 3},
  "n": 5
})");
}

TEST_CASE("find_at answers the member at an exact pointer, or null when any step is missing") {
  REQUIRE(find_at(kDoc, Pointer("/axes/x/modes/1/freq_hz")) != nullptr);
  CHECK(*find_at(kDoc, Pointer("/axes/x/modes/1/freq_hz")) == 61.0);
  CHECK(find_at(kDoc, Pointer("/axes/x/modes/2/freq_hz")) == nullptr);  // index past the end
  CHECK(find_at(kDoc, Pointer("/axes/x/modes/first")) == nullptr);      // not an index
  CHECK(find_at(kDoc, Pointer("/n/value")) == nullptr);                 // a step into a number
  CHECK(find_at(kDoc, Pointer("/axes/y")) == nullptr);
  CHECK(find_at(kDoc, Pointer("/axes/x/modes/99999999999999999999999")) == nullptr);
  CHECK(value_at_or_null(kDoc, Pointer("/axes/z/freq_hz")).is_null());
  CHECK(value_at_or_null(kDoc, Pointer("/n")) == 5);
}

TEST_CASE("dotted results paths become pointers, keys with '/' and '~' escaped") {
  CHECK(pointer_from_dotted("axes.x.modes[1].freq_hz").to_string() == "/axes/x/modes/1/freq_hz");
  CHECK(pointer_from_dotted("a/b.c~d").to_string() == "/a~1b/c~0d");
  CHECK(*json_at(kDoc, "a/b.c~d") == 3);
  CHECK(*json_at(kDoc, "axes.x.modes[0].freq_hz") == 44.2);
  CHECK(json_at(kDoc, "axes.x.modes[2].freq_hz") == nullptr);
  CHECK_THROWS_AS(pointer_from_dotted("axes.x.modes[x]"), tunekit::InputError);
  CHECK_THROWS_AS(pointer_from_dotted("axes.x.modes[1"), tunekit::InputError);
  CHECK(json_at(kDoc, "axes.x.modes[x]") == nullptr);  // malformed: absent, never an internal error
}

TEST_CASE("a --require path names a number by its last segment with the others in order before it") {
  const auto number = split_requirement_path("axes.x.modes[0].freq_hz");
  CHECK(number == std::vector<std::string>{"axes", "x", "modes", "[0]", "freq_hz"});
  CHECK(requirement_path_matches(split_requirement_path("freq_hz"), number));
  CHECK(requirement_path_matches(split_requirement_path("x.freq_hz"), number));
  CHECK(requirement_path_matches(split_requirement_path("axes.x.modes[0].freq_hz"), number));
  CHECK_FALSE(requirement_path_matches(split_requirement_path("y.freq_hz"), number));
  CHECK_FALSE(requirement_path_matches(split_requirement_path("freq_hz.x"), number));  // order matters
  CHECK_FALSE(requirement_path_matches(split_requirement_path("x"), number));          // the last must coincide
  const auto o = evaluate_requirement(parse_requirement("modes[1].freq_hz>50"), kDoc);
  CHECK(o.met);
  CHECK(o.pointer.to_string() == "/axes/x/modes/1/freq_hz");
}

TEST_CASE("read_json_file locates a syntax error at its line and column") {
  const auto path = tunekit::test::write_scratch("json_access_bad.json", "{\n  \"a\": 1,\n  \"b\": tru\n}\n");
  try {
    (void)read_json_file(path);
    FAIL("no error");
  } catch (const tunekit::InputError& e) {
    CHECK(e.location().rfind(path + ":3:", 0) == 0);
  }
  const auto good = tunekit::test::write_scratch("json_access_good.json", "{\"a\": [1, 2]}");
  std::string bytes;
  CHECK(read_json_file(good, &bytes)["a"][1] == 2);
  CHECK(bytes == "{\"a\": [1, 2]}");
  CHECK_THROWS_AS(read_json_file(path + ".missing"), tunekit::InputError);
}

TEST_CASE("a JSON library error is said in plain words, without the library's tag") {
  const nlohmann::json doc = nlohmann::json::parse(R"({"model": 3, "params": [1]})");
  // Each error is the library's own, raised by a real misuse, so its wording is the library's.
  auto what_of = [](const auto& misuse) -> std::string {
    try {
      (void)misuse();
    } catch (const nlohmann::json::exception& e) {
      return e.what();
    }
    return {};
  };
  const std::string type = what_of([&] { return doc.at("model").get<std::string>(); });
  const std::string missing = what_of([&] { return doc.at("name"); });
  const std::string index = what_of([&] { return doc.at("params").at(4); });
  const std::string syntax = what_of([] { return nlohmann::json::parse("{\"a\": tru}"); });
  for (const auto& w : {type, missing, index, syntax}) {
    REQUIRE(w.find("[json.exception.") == 0);
    CHECK(tunekit::core::plain_json_error(w).find("json.exception") == std::string::npos);
  }
  CHECK(tunekit::core::plain_json_error(type) == "text was expected, but found a number");
  CHECK(tunekit::core::plain_json_error(missing) == "the member 'name' is missing");
  CHECK(tunekit::core::plain_json_error(index) == "a list has no item 4");
  CHECK(tunekit::core::plain_json_error(syntax).rfind("syntax error at line 1, column ", 0) == 0);
}

TEST_CASE("a results file of the wrong shape is refused in plain words") {
  const auto path =
      tunekit::test::write_scratch("rheo_model_number.json", R"({"results": {"model": 3, "params": {}}})");
  const auto r = tunekit::test::run_cli({"nozzle", "--rheology", path, "--temperature", "230", "--flow", "3"});
  INFO(r.err);
  CHECK(r.code == 2);
  CHECK(r.err.find("json.exception") == std::string::npos);
  CHECK(r.err.find("text was expected, but found a number") != std::string::npos);
}
