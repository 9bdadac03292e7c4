// Transparent huge pages for a parsed file's columns: advice that the kernel records on the
// buffer's memory and that changes none of its bytes.
#include <catch2/catch.hpp>

#include <cstdint>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "tunekit/core/huge_pages.hpp"

namespace {

// The "VmFlags:" line of the mapping of /proc/self/smaps that contains `address` ("" if none).
std::string vm_flags_at(const void* address) {
  const auto a = reinterpret_cast<std::uintptr_t>(address);
  std::ifstream smaps("/proc/self/smaps");
  std::string line;
  bool inside = false;
  while (std::getline(smaps, line)) {
    std::uintptr_t lo = 0, hi = 0;
    char dash = 0;
    std::istringstream range(line);
    if (range >> std::hex >> lo >> dash >> hi && dash == '-') inside = lo <= a && a < hi;
    if (inside && line.rfind("VmFlags:", 0) == 0) return line;
  }
  return "";
}

// Whether this kernel offers transparent huge pages to a buffer that asks for them.
bool kernel_offers_huge_pages() {
  std::ifstream enabled("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string modes;
  return std::getline(enabled, modes) && modes.find("[never]") == std::string::npos;
}

}  // namespace

TEST_CASE("huge-page advice marks a large buffer's whole 2 MiB pages and changes none of its bytes") {
  std::vector<double> column(std::size_t{8} << 17);  // 8 MiB: at least three whole 2 MiB pages
  for (std::size_t i = 0; i < column.size(); ++i) column[i] = static_cast<double>(i) * 0.5;
  tunekit::core::advise_huge_pages(column.data(), column.size() * sizeof(double));
  for (std::size_t i = 0; i < column.size(); i += 4099) CHECK(column[i] == static_cast<double>(i) * 0.5);
  const double* middle = column.data() + column.size() / 2;  // inside a whole 2 MiB page
  if (kernel_offers_huge_pages()) CHECK(vm_flags_at(middle).find(" hg") != std::string::npos);
  // Small buffers and no buffer are left alone.
  std::vector<double> small(1000, 1.0);
  tunekit::core::advise_huge_pages(small.data(), small.size() * sizeof(double));
  tunekit::core::advise_huge_pages(nullptr, std::size_t{64} << 20);
  CHECK(small[999] == 1.0);
  if (kernel_offers_huge_pages()) CHECK(vm_flags_at(small.data()).find(" hg") == std::string::npos);
}
