// The history opens only its own SQLite databases: another program's database is refused
// before anything in it changes, and SQLite's in-memory and URI names, where a record would be
// lost, are refused for --record; each with one line and exit code 2.
#include <sqlite3.h>

#include <filesystem>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "test_support.hpp"

using tunekit::test::dataset;
using tunekit::test::read_text;
using tunekit::test::run_cli;
using tunekit::test::scratch_dir;
namespace fs = std::filesystem;

// The whole file in a namespace of its own: the test areas are unity builds, and other files
// have helpers of the same names.
namespace test_history_foreign {

void sql(const std::string& db, const std::string& statement) {
  sqlite3* h = nullptr;
  REQUIRE(sqlite3_open(db.c_str(), &h) == SQLITE_OK);
  REQUIRE(sqlite3_exec(h, statement.c_str(), nullptr, nullptr, nullptr) == SQLITE_OK);
  sqlite3_close(h);
}

/// The names of the tables of the SQLite file `db`.
std::vector<std::string> tables(const std::string& db) {
  sqlite3* h = nullptr;
  REQUIRE(sqlite3_open_v2(db.c_str(), &h, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK);
  std::vector<std::string> out;
  sqlite3_exec(
      h, "SELECT name FROM sqlite_master WHERE type = 'table' ORDER BY name",
      [](void* v, int, char** cols, char**) {
        static_cast<std::vector<std::string>*>(v)->push_back(cols[0]);
        return 0;
      },
      &out, nullptr);
  sqlite3_close(h);
  return out;
}

std::vector<std::string> step_record(const std::string& db) {
  return {"step",     dataset("liquefier/synthetic_steps.csv"),
          "--time",   "time",
          "--input",  "feed",
          "--output", "force",
          "--record", "--machine-id",
          "m1",       "--db",
          db};
}

bool one_line(const std::string& err) {
  return err.rfind("tunekit: error: ", 0) == 0 && err.find('\n') == err.size() - 1;
}

TEST_CASE("history: another program's SQLite database is refused and left unchanged", "[history]") {
  const std::string dir = scratch_dir("history_foreign");
  const std::string db = dir + "/o.sqlite";
  sql(db, "CREATE TABLE foo(a)");
  const std::string before = read_text(db);

  const auto rec = run_cli(step_record(db));
  INFO(rec.err);
  CHECK(rec.code == 2);
  CHECK(one_line(rec.err));
  CHECK(rec.err.find("not a tunekit history database") != std::string::npos);

  const auto list = run_cli({"history", "list", "--db", db});
  INFO(list.err);
  CHECK(list.code == 2);
  CHECK(one_line(list.err));

  CHECK(tables(db) == std::vector<std::string>{"foo"});
  CHECK(read_text(db) == before);
  CHECK_FALSE(fs::exists(db + "-wal"));
}

TEST_CASE("history: a database with another application id is refused, tunekit's own opens again", "[history]") {
  const std::string dir = scratch_dir("history_application_id");
  const std::string other = dir + "/other.sqlite";
  sql(other, "PRAGMA application_id = 1234");
  CHECK(run_cli(step_record(other)).code == 2);

  const std::string own = dir + "/own.sqlite";
  REQUIRE(run_cli(step_record(own)).code == 0);
  REQUIRE(run_cli(step_record(own)).code == 0);
  const auto list = run_cli({"history", "list", "--db", own, "--json"});
  REQUIRE(list.code == 0);
  CHECK(list.out.find("m1") != std::string::npos);
}

TEST_CASE("history: --record to ':memory:' or a 'file:' URI is refused, not lost", "[history]") {
  const std::string dir = scratch_dir("history_uri");
  fs::current_path(dir);
  for (const std::string& db :
       {std::string("file:x.sqlite?mode=memory"), std::string(":memory:"), std::string("file:") + dir + "/y.sqlite"}) {
    const auto r = run_cli(step_record(db));
    INFO(db << ": " << r.err);
    CHECK(r.code == 2);
    CHECK(one_line(r.err));
    CHECK(r.err.find("must be a file path") != std::string::npos);
  }
  CHECK_FALSE(fs::exists(dir + "/y.sqlite"));
}

}  // namespace test_history_foreign
