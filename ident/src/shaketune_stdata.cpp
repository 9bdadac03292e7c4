#include "tunekit/ident/shaketune_stdata.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <iterator>
#include <memory>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <zstd.h>

#include "tunekit/core/json_error_text.hpp"
#include "tunekit/core/error.hpp"

namespace tunekit::ident {
namespace {

// The most a .stdata file may expand, as decompressed over compressed bytes: Shake&Tune's
// JSON samples compress about 7-fold (the bundled sweeps: 2.9 MB -> 21 MB); a file that
// expands 200-fold is not a measurement but a stream of repeated bytes. Small files may
// always reach kMinStdataCap bytes.
constexpr std::size_t kMaxStdataExpansion = 200;
constexpr std::size_t kMinStdataCap = std::size_t{64} << 20;

// The whole Zstandard stream (one or several frames) decompressed, refused as soon as it
// grows past its cap (the expansion bound, at most kMaxStdataBytes): a small file that
// would expand to gigabytes stops after its cap, not after decompressing everything.
std::string stdata_decompress(const std::string& path, std::string_view bytes) {
  std::unique_ptr<ZSTD_DCtx, decltype(&ZSTD_freeDCtx)> ctx(ZSTD_createDCtx(), &ZSTD_freeDCtx);
  if (!ctx) throw InputError("cannot allocate a Zstandard decoder", path);
  const std::size_t cap = std::min(
      kMaxStdataBytes,
      std::max(kMinStdataCap, bytes.size() * kMaxStdataExpansion));  // no overflow: input files are at most 1 GiB
  std::string out;
  std::string chunk(ZSTD_DStreamOutSize(), '\0');
  ZSTD_inBuffer in{bytes.data(), bytes.size(), 0};
  std::size_t last = 0;
  for (;;) {
    ZSTD_outBuffer ob{chunk.data(), chunk.size(), 0};
    last = ZSTD_decompressStream(ctx.get(), &ob, &in);
    if (ZSTD_isError(last))
      throw InputError(fmt::format("not a readable Shake&Tune .stdata file: Zstandard error '{}' at byte {}",
                                   ZSTD_getErrorName(last), in.pos),
                       path);
    if (out.size() + ob.pos > cap)
      throw InputError(fmt::format("decompresses to more than {} bytes ({} times its {} bytes, or {} bytes for any "
                                   "file); not a Shake&Tune measurement file",
                                   cap, kMaxStdataExpansion, bytes.size(), kMinStdataCap),
                       path);
    out.append(chunk.data(), ob.pos);
    // Done when the input is consumed and either the last frame is complete (0; calling again
    // would start a new frame) or the decoder had room to spare (nothing left to flush).
    if (in.pos == in.size && (last == 0 || ob.pos < ob.size)) break;
  }
  if (last != 0)
    throw InputError("the Zstandard stream ends in the middle of a frame (a truncated .stdata file)", path);
  return out;
}

// axis_X_... -> 'x' (Shake&Tune's input-shaper measurements); 0 for any other name.
char stdata_axis_from_name(const std::string& name) {
  if (name.size() >= 6 && name.compare(0, 5, "axis_") == 0) {
    const char a = static_cast<char>(std::tolower(static_cast<unsigned char>(name[5])));
    if ((a == 'x' || a == 'y' || a == 'z') && (name.size() == 6 || name[6] == '_')) return a;
  }
  return 0;
}

}  // namespace

bool is_shaketune_stdata(std::string_view bytes) {
  return bytes.size() >= 4 && static_cast<unsigned char>(bytes[0]) == 0x28 &&
         static_cast<unsigned char>(bytes[1]) == 0xB5 && static_cast<unsigned char>(bytes[2]) == 0x2F &&
         static_cast<unsigned char>(bytes[3]) == 0xFD;
}

std::vector<StdataMeasurement> load_shaketune_stdata(const std::string& path, std::string_view bytes,
                                                     const AccelInputOptions& options) {
  const std::string text = stdata_decompress(path, bytes);
  std::vector<StdataMeasurement> out;
  std::size_t line_no = 0;
  for (std::size_t b = 0; b < text.size();) {
    auto e = text.find('\n', b);
    if (e == std::string::npos) e = text.size();
    const std::string_view line(text.data() + b, e - b);
    b = e + 1;
    ++line_no;
    if (line.find_first_not_of(" \t\r") == std::string_view::npos) continue;
    nlohmann::json m;
    try {
      m = nlohmann::json::parse(line);
    } catch (const nlohmann::json::exception& ex) {
      throw InputError(fmt::format("decompressed line {} is not JSON ({})", line_no, core::plain_json_error(ex.what())),
                       path);
    }
    if (!m.is_object() || !m.contains("samples") || !m["samples"].is_array())
      throw InputError(
          fmt::format("decompressed line {} is not a Shake&Tune measurement (no \"samples\" array)", line_no), path);
    StdataMeasurement meas;
    meas.name = m.contains("name") && m["name"].is_string() ? m["name"].get<std::string>()
                                                            : fmt::format("measurement_{}", out.size() + 1);
    // The samples in Klipper's raw CSV layout, each number printed as Klipper prints it
    // (%.6f), so that they take exactly the path of a raw_data_*.csv.
    const auto& samples = m["samples"];
    std::string csv = "#time,accel_x,accel_y,accel_z\n";
    csv.reserve(samples.size() * 48 + csv.size());
    auto it = std::back_inserter(csv);
    std::size_t k = 0;
    for (const auto& s : samples) {
      if (!s.is_array() || s.size() != 4)
        throw InputError(
            fmt::format("measurement '{}', sample {}: expected [time, accel_x, accel_y, accel_z]", meas.name, k), path);
      double v[4];
      for (std::size_t c = 0; c < 4; ++c) {
        if (!s[c].is_number())
          throw InputError(fmt::format("measurement '{}', sample {}: value {} is not a number", meas.name, k, c), path);
        v[c] = s[c].get<double>();
        if (!std::isfinite(v[c]))
          throw InputError(fmt::format("measurement '{}', sample {}: value {} is not finite", meas.name, k, c), path);
      }
      fmt::format_to(it, "{:.6f},{:.6f},{:.6f},{:.6f}\n", v[0], v[1], v[2], v[3]);
      ++k;
    }
    AccelInputOptions o = options;
    o.time_column = AccelInputOptions{}.time_column;
    o.accel_columns = {"accel_x", "accel_y", "accel_z"};
    o.excitation_column.clear();
    if (o.axis == 0) o.axis = stdata_axis_from_name(meas.name);
    meas.record = load_accel_csv(path + "[" + meas.name + "]", csv, o);
    out.push_back(std::move(meas));
  }
  if (out.empty()) throw InputError("the Shake&Tune .stdata file holds no measurement", path);
  return out;
}

}  // namespace tunekit::ident
