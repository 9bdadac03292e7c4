#include "history_fixture.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <pwd.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <stdexcept>

#include "test_support.hpp"
#include "tunekit/history/database.hpp"

extern char** environ;

namespace tunekit::test {
namespace {

namespace fs = std::filesystem;

std::string shell_quote(const std::string& s) {
  std::string o = "'";
  for (char c : s) o += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return o + "'";
}

// Debian installs the server binaries under /usr/lib/postgresql/<major>/bin; the newest wins.
std::string postgres_bin_dir() {
  if (const char* e = std::getenv("TUNEKIT_TEST_PG_BIN"); e != nullptr && *e != '\0') return e;
  std::vector<fs::path> found;
  std::error_code ec;
  for (const auto& d : fs::directory_iterator("/usr/lib/postgresql", ec))
    if (fs::exists(d.path() / "bin" / "pg_ctl") && fs::exists(d.path() / "bin" / "initdb"))
      found.push_back(d.path() / "bin");
  if (found.empty()) return "";
  std::sort(found.begin(), found.end(), [](const fs::path& a, const fs::path& b) {
    return std::atoi(a.parent_path().filename().c_str()) < std::atoi(b.parent_path().filename().c_str());
  });
  return found.back().string();
}

int free_tcp_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = 0;
  socklen_t len = sizeof a;
  if (::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 ||
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len) != 0) {
    ::close(fd);
    throw std::runtime_error("no free TCP port on 127.0.0.1");
  }
  const int port = ntohs(a.sin_port);
  ::close(fd);
  return port;
}

class PostgresServer {
 public:
  PostgresServer() {
    bin_ = postgres_bin_dir();
    if (bin_.empty()) {
      skip_reason_ =
          "PostgreSQL server binaries not found under /usr/lib/postgresql/*/bin (scripts/install-deps installs "
          "the Debian package postgresql)";
      return;
    }
    char tmpl[] = "/tmp/tunekit-pg-XXXXXX";
    if (::mkdtemp(tmpl) == nullptr) throw std::runtime_error("mkdtemp failed");
    dir_ = tmpl;
    // As root the server must run as an unprivileged user (postgres refuses root).
    if (::geteuid() == 0) {
      const passwd* pw = ::getpwnam("nobody");
      if (pw == nullptr) throw std::runtime_error("running as root and there is no user 'nobody' to run PostgreSQL as");
      if (::chown(dir_.c_str(), pw->pw_uid, pw->pw_gid) != 0) throw std::runtime_error("cannot chown " + dir_);
      as_user_ = "runuser -u nobody -- ";
    }
    port_ = free_tcp_port();
    run(as_user_ + shell_quote(bin_ + "/initdb") + " -D " + shell_quote(dir_ + "/data") +
        " -A trust -U tunekit -E UTF8 --no-sync > " + shell_quote(dir_ + "/initdb.log") + " 2>&1");
    // fsync off: the tests kill clients, not the server, and need no durability across a power cut.
    run(as_user_ + shell_quote(bin_ + "/pg_ctl") + " -D " + shell_quote(dir_ + "/data") + " -l " +
        shell_quote(dir_ + "/server.log") + " -w -t 60 -o " +
        shell_quote("-p " + std::to_string(port_) + " -k " + dir_ +
                    " -c listen_addresses=127.0.0.1 -c fsync=off -c max_connections=200") +
        " start > /dev/null 2>&1");
    started_ = true;
  }
  ~PostgresServer() {
    if (started_)
      std::system((as_user_ + shell_quote(bin_ + "/pg_ctl") + " -D " + shell_quote(dir_ + "/data") +
                   " -m immediate -w stop > /dev/null 2>&1")
                      .c_str());
    if (!dir_.empty()) {
      std::error_code ec;
      fs::remove_all(dir_, ec);
    }
  }
  const std::string& skip_reason() const { return skip_reason_; }
  std::string log() const { return started_ ? read_text(dir_ + "/server.log") : ""; }
  std::string create_database(const std::string& name) {
    const std::string base = "postgresql://tunekit@127.0.0.1:" + std::to_string(port_);
    auto admin = history::connect(base + "/postgres");
    admin->execute("DROP DATABASE IF EXISTS " + name);
    admin->execute("CREATE DATABASE " + name);
    return base + "/" + name;
  }

 private:
  void run(const std::string& cmd) {
    if (std::system(cmd.c_str()) != 0)
      throw std::runtime_error("PostgreSQL test server: command failed: " + cmd + " (logs in " + dir_ + ")");
  }
  std::string bin_, dir_, as_user_, skip_reason_;
  int port_ = 0;
  bool started_ = false;
};

std::string db_name_of(const std::string& name) {
  std::string o = "t_";
  for (char c : name) o += std::isalnum(static_cast<unsigned char>(c)) ? static_cast<char>(std::tolower(c)) : '_';
  return o.substr(0, 60);
}

std::unique_ptr<PostgresServer>& postgres_server() {
  static std::unique_ptr<PostgresServer> server;
  return server;
}

}  // namespace

std::string postgres_server_log() { return postgres_server() ? postgres_server()->log() : ""; }

TestDatabase fresh_database(const std::string& backend, const std::string& name) {
  TestDatabase db{backend, "", ""};
  if (backend == "sqlite") {
    db.url = scratch_dir("history-" + name) + "/history.sqlite";
    return db;
  }
  auto& server = postgres_server();
  if (!server) server = std::make_unique<PostgresServer>();
  if (!server->skip_reason().empty()) {
    db.skip_reason = server->skip_reason();
    return db;
  }
  db.url = server->create_database(db_name_of(name));
  return db;
}

pid_t spawn_process(const std::vector<std::string>& argv, const std::string& log_path) {
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, log_path.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  posix_spawn_file_actions_adddup2(&fa, 1, 2);
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, argv[0].c_str(), &fa, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) throw std::runtime_error("cannot start " + argv[0]);
  return pid;
}

int wait_process(pid_t pid) {
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return -1;
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return -1;
}

}  // namespace tunekit::test
