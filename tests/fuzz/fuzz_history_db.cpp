// The history path on arbitrary database files: the bytes are written to a file and opened as a
// history (tunekit::history::Store), then listed. Two outcomes are accepted: a result (the bytes
// were tunekit's own database, or an empty file it made one) or tunekit's own error (another
// program's database, not a database at all, a newer schema). The seeds are a tunekit history
// with records, another program's SQLite file and an empty file.
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "fuzz_common.hpp"
#include "tunekit/history/store.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size > 4 * 1024 * 1024) return -1;
  static const std::string dir = [] {
    const auto d = std::filesystem::temp_directory_path() / ("tunekit-fuzz-history-" + std::to_string(::getpid()));
    std::filesystem::create_directories(d);
    return d.string();
  }();
  const std::string path = dir + "/h.sqlite";
  for (const char* suffix : {"", "-wal", "-shm", "-journal"}) std::remove((path + suffix).c_str());
  {
    std::ofstream f(path, std::ios::binary);
    f.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  tunekit::fuzz::expect_result_or_error([&] {
    tunekit::history::Store store(path);
    for (const auto& m : store.machines()) {
      for (const auto& r : store.records(m.machine_id)) store.get(r.id);
      store.series(m.machine_id);
    }
  });
  return 0;
}
