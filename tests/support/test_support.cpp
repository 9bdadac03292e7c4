#include "test_support.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <array>
#include <cctype>
#include <cmath>
#include <regex>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "tunekit/cli/run_cli.hpp"

namespace tunekit::test {

CliRun run_cli(const std::vector<std::string>& args) {
  std::ostringstream out, err;
  CliRun r;
  r.code = tunekit::cli::run_cli(args, out, err);
  r.out = out.str();
  r.err = err.str();
  return r;
}

CliRun run_reproduce_command(const std::string& run_dir, const std::string& command,
                             const std::vector<std::string>& extra) {
  std::istringstream words(command);
  std::string word;
  if (!(words >> word) || word != "tunekit") throw std::runtime_error("not a tunekit command: " + command);
  std::vector<std::string> args;
  while (words >> word) args.push_back(std::filesystem::exists(run_dir + "/" + word) ? run_dir + "/" + word : word);
  args.insert(args.end(), extra.begin(), extra.end());
  return run_cli(args);
}

namespace {

// What identifies the build that made a shared run: the tunekit executable's size and time.
std::string build_stamp() {
  const std::filesystem::path exe(TUNEKIT_EXE);
  const auto t = std::filesystem::last_write_time(exe).time_since_epoch().count();
  return std::to_string(std::filesystem::file_size(exe)) + " " + std::to_string(t);
}

void write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary);
  f << text;
}

// Holds an exclusive flock on `path` for the object's lifetime (released by the kernel if the
// process dies).
class FileLock {
 public:
  explicit FileLock(const std::filesystem::path& path) : fd_(::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644)) {
    if (fd_ < 0 || ::flock(fd_, LOCK_EX) != 0) throw std::runtime_error("cannot lock " + path.string());
  }
  ~FileLock() { ::close(fd_); }
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;

 private:
  int fd_;
};

SharedCalibration load_or_run_default_calibration() {
  const auto base = std::filesystem::path(TUNEKIT_TEST_TMP_DIR) / "shared_default_calibration";
  std::filesystem::create_directories(base.parent_path());
  FileLock lock(base.string() + ".lock");
  SharedCalibration c{(base / "run").string(), {}};
  const std::string stamp = build_stamp();
  if (read_text((base / "stamp").string()) != stamp) {
    std::filesystem::remove_all(base);
    std::filesystem::create_directories(base);
    const auto cli = run_cli({"calibrate", "--machine", "sim", "--out", c.dir});
    write_text(base / "code", std::to_string(cli.code));
    write_text(base / "out", cli.out);
    write_text(base / "err", cli.err);
    write_text(base / "stamp", stamp);  // last: a run cut short is run again
  }
  c.cli.code = std::stoi(read_text((base / "code").string()));
  c.cli.out = read_text((base / "out").string());
  c.cli.err = read_text((base / "err").string());
  return c;
}

}  // namespace

const SharedCalibration& default_calibration() {
  static const SharedCalibration c = load_or_run_default_calibration();
  return c;
}

CliRun run_exe(const std::string& args) { return run_exe_prefixed("", args); }

CliRun run_exe_prefixed(const std::string& prefix, const std::string& args) {
  // One stderr file per process and call: ctest runs test cases in parallel processes.
  static int calls = 0;
  const auto dir = std::filesystem::path(TUNEKIT_TEST_TMP_DIR) / "run_exe";
  std::filesystem::create_directories(dir);
  const std::string err_path =
      (dir / ("stderr." + std::to_string(::getpid()) + "." + std::to_string(++calls))).string();
  const std::string cmd = prefix + std::string(TUNEKIT_EXE) + " " + args + " 2>" + err_path;
  CliRun r;
  FILE* p = ::popen(cmd.c_str(), "r");
  if (!p) throw std::runtime_error("popen failed");
  std::array<char, 4096> buf{};
  std::size_t n;
  while ((n = std::fread(buf.data(), 1, buf.size(), p)) > 0) r.out.append(buf.data(), n);
  const int status = ::pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream f(err_path);
  std::stringstream ss;
  ss << f.rdbuf();
  r.err = ss.str();
  return r;
}

namespace {

std::size_t embedded_base64_length(const std::string& html, const std::string& id,
                                   const std::vector<std::string>& mimes) {
  const std::string open = "<figure id=\"plot-" + id + "\"><img alt=\"";
  auto pos = html.find(open);
  if (pos == std::string::npos) return 0;
  pos = html.find("\" src=\"data:", pos);
  if (pos == std::string::npos) return 0;
  pos += std::string("\" src=\"data:").size();
  bool known = false;
  for (const auto& m : mimes)
    if (html.compare(pos, m.size() + 8, m + ";base64,") == 0) {
      pos += m.size() + 8;
      known = true;
      break;
    }
  if (!known) return 0;
  std::size_t n = 0;
  while (pos + n < html.size() && (std::isalnum(static_cast<unsigned char>(html[pos + n])) || html[pos + n] == '+' ||
                                   html[pos + n] == '/' || html[pos + n] == '='))
    ++n;
  return (pos + n < html.size() && html[pos + n] == '"') ? n : 0;
}

}  // namespace

std::size_t embedded_image_base64_length(const std::string& html, const std::string& id) {
  return embedded_base64_length(html, id, {"image/svg+xml", "image/png"});
}

std::size_t embedded_png_base64_length(const std::string& html, const std::string& id) {
  return embedded_base64_length(html, id, {"image/png"});
}

std::vector<SummaryCell> summary_cells(const std::string& html) {
  std::vector<SummaryCell> cells;
  const auto begin = html.find("<table id=\"summary\">");
  const auto end = html.find("</table>", begin);
  if (begin == std::string::npos || end == std::string::npos) return cells;
  const std::string table = html.substr(begin, end - begin);
  const std::regex cell("<td class=\"num\" data-path=\"([^\"]+)\" data-value=\"([^\"]+)\">([^<]+)</td>");
  for (auto it = std::sregex_iterator(table.begin(), table.end(), cell); it != std::sregex_iterator(); ++it)
    cells.push_back({(*it)[1].str(), (*it)[2].str(), (*it)[3].str()});
  return cells;
}

std::string dataset(const std::string& relative) { return std::string(TUNEKIT_DATASETS_DIR) + "/" + relative; }

std::string scratch_dir(const std::string& name) {
  const auto dir = std::filesystem::path(TUNEKIT_TEST_TMP_DIR) / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

std::string write_scratch(const std::string& name, const std::string& content) {
  const auto dir = std::filesystem::path(TUNEKIT_TEST_TMP_DIR) / "files";
  std::filesystem::create_directories(dir);
  const auto path = dir / name;
  // Test cases run as parallel processes and several write the same named file: each writes its
  // own temporary and renames it into place, so a reader (a tunekit child that maps the file)
  // never sees it truncated under it.
  const auto tmp = dir / (name + ".tmp" + std::to_string(::getpid()));
  {
    std::ofstream f(tmp, std::ios::binary);
    f << content;
  }
  std::filesystem::rename(tmp, path);
  return path.string();
}

std::string read_text(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

nlohmann::json read_json(const std::string& path) { return nlohmann::json::parse(read_text(path)); }

std::vector<std::string> shell_words(const std::string& line) {
  std::vector<std::string> words;
  std::string cur;
  bool in_word = false;
  char quote = 0;
  for (char c : line) {
    if (quote) {
      if (c == quote) quote = 0;
      else cur += c;
      continue;
    }
    if (c == '\'' || c == '"') {
      quote = c;
      in_word = true;
    } else if (c == ' ' || c == '\t') {
      if (in_word) words.push_back(cur);
      cur.clear();
      in_word = false;
    } else {
      cur += c;
      in_word = true;
    }
  }
  if (in_word) words.push_back(cur);
  return words;
}

std::vector<double> inverse_normal_diagonal(const std::vector<std::vector<double>>& cols) {
  const std::size_t k = cols.size();
  std::vector<std::vector<double>> a(k, std::vector<double>(2 * k, 0.0));
  for (std::size_t r = 0; r < k; ++r) {
    for (std::size_t c = 0; c < k; ++c)
      for (std::size_t i = 0; i < cols[r].size(); ++i) a[r][c] += cols[r][i] * cols[c][i];
    a[r][k + r] = 1;
  }
  for (std::size_t c = 0; c < k; ++c) {
    std::size_t piv = c;
    for (std::size_t r = c + 1; r < k; ++r)
      if (std::abs(a[r][c]) > std::abs(a[piv][c])) piv = r;
    std::swap(a[c], a[piv]);
    const double d = a[c][c];
    for (auto& x : a[c]) x /= d;
    for (std::size_t r = 0; r < k; ++r)
      if (r != c) {
        const double f = a[r][c];
        for (std::size_t q = 0; q < 2 * k; ++q) a[r][q] -= f * a[c][q];
      }
  }
  std::vector<double> diag;
  for (std::size_t j = 0; j < k; ++j) diag.push_back(a[j][k + j]);
  return diag;
}

}  // namespace tunekit::test
