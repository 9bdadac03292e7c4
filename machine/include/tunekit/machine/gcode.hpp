#pragma once
// G-code lines: parsing into words, Marlin's line numbers and checksums, and a small
// interpreter of the motion state (positions, absolute/relative modes, feed rate, acceleration)
// shared by the safety check and the simulated printer. Units: mm, mm/s, mm/s^2 inside
// (G-code's F is mm/min and is converted on parsing).

#include <array>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace tunekit::machine {

/// The words of one line by name: a line has a handful, so they are kept in one small vector
/// and searched in order (a map allocates a node per word, and the gate, the link's last check
/// and the simulator parse every line of every protocol). A repeated word keeps its last value.
template <class V>
class WordMap {
 public:
  V& operator[](const std::string& k) {
    for (auto& e : words_)
      if (e.first == k) return e.second;
    if (words_.empty()) words_.reserve(kTypicalWords);
    return words_.emplace_back(k, V{}).second;
  }
  /// The value of word k, or nullptr.
  const V* find(const std::string& k) const {
    for (const auto& e : words_)
      if (e.first == k) return &e.second;
    return nullptr;
  }
  std::size_t count(const std::string& k) const { return find(k) != nullptr ? 1 : 0; }
  bool empty() const { return words_.empty(); }
  std::size_t size() const { return words_.size(); }
  auto begin() const { return words_.begin(); }
  auto end() const { return words_.end(); }

 private:
  static constexpr std::size_t kTypicalWords = 6;  // G1 X Y Z E F
  std::vector<std::pair<std::string, V>> words_;
};

struct GcodeWords {
  std::string command;             ///< "G1", "M204", or an extended name ("SET_VELOCITY_LIMIT")
  WordMap<double> args;            ///< "X" -> 10.0; extended commands: "ACCEL" -> 3000
  WordMap<std::string> text_args;  ///< arguments that are not numbers
  bool has(const std::string& k) const { return args.count(k) != 0; }
  double get(const std::string& k, double fallback) const;
};

/// Parses one line; comments (';' and parentheses) and any N<line>/ *<checksum> are dropped.
/// Returns nullopt for an empty or comment-only line.
std::optional<GcodeWords> parse_gcode(std::string_view line);

/// Marlin's checksum: XOR of every byte before the '*'.
int gcode_checksum(std::string_view text);
/// "N<n> <command>*<checksum>".
std::string numbered_line(long n, std::string_view command);

struct NumberedLine {
  std::optional<long> number;   ///< N, when present
  std::optional<int> checksum;  ///< *, when present
  bool checksum_ok = true;      ///< false if a checksum is present and wrong
  std::string body;             ///< the command without N and checksum
};
NumberedLine split_numbered(std::string_view raw);

/// Axis order in positions: x, y, z, e.
inline constexpr std::array<const char*, 4> kAxisNames{"x", "y", "z", "e"};

struct GcodeMove {
  std::array<double, 4> start{};  ///< mm
  std::array<double, 4> end{};    ///< mm
  double feed_mm_s = 0;           ///< path speed (XYZ length, or E for extruder-only moves)
  double accel_mm_s2 = 0;         ///< path acceleration in force for this move
  double length_mm() const;       ///< XYZ length, or |E| for an extruder-only move
  bool extruder_only() const;
  /// Per-axis share of the path: |d axis| / length (0..1; E can exceed 1 in XY moves).
  std::array<double, 4> unit() const;
};

/// Tracks the machine state a G-code stream sets up. Knows G0/G1, G4, G90/G91, M82/M83, G92,
/// M204 (S, P print, T travel, R retract), M201 (per-axis maxima), SET_VELOCITY_LIMIT ACCEL=,
/// M104/M109 (S or R)/M140/M190 (temperatures). A move's acceleration is the one its kind gets
/// (extrude-only: M204 R, else M201 E; without E: travel; else print), capped by M201.
class GcodeInterpreter {
 public:
  GcodeInterpreter();
  /// Applies one parsed line; returns the move when it is a G0/G1 with displacement.
  std::optional<GcodeMove> apply(const GcodeWords& w);
  const std::array<double, 4>& position() const { return pos_; }
  double feed_mm_s() const { return feed_mm_s_; }
  double accel_mm_s2() const { return accel_mm_s2_; }
  /// Dwell requested by the last G4, seconds (0 if the last line was not a G4).
  double dwell_s() const { return dwell_s_; }
  /// Set temperatures seen (M104/M109 -> hotend, M140/M190 -> bed), degC.
  std::optional<double> hotend_c, bed_c;

 private:
  std::array<double, 4> pos_{};
  bool absolute_xyz_ = true;
  bool absolute_e_ = false;
  double feed_mm_s_ = 25;
  double accel_mm_s2_ = 1000;  ///< print acceleration
  double travel_accel_ = 1000;
  std::optional<double> retract_accel_;
  std::array<std::optional<double>, 4> max_accel_{};
  double dwell_s_ = 0;
};

}  // namespace tunekit::machine
