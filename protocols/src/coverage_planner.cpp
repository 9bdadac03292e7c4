#include "tunekit/protocols/coverage_planner.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/machine/trajectory.hpp"

namespace tunekit::protocols {
namespace {

struct CoverageGrid {
  int nx = 0, ny = 0;
  double x0 = 0, y0 = 0, cell = 0;
  std::vector<char> print;  // 1: a cell to print
  bool inside(int i, int j) const { return i >= 0 && j >= 0 && i < nx && j < ny; }
  bool printable(int i, int j) const { return inside(i, j) && print[static_cast<std::size_t>(j * nx + i)] != 0; }
  double cx(int i) const { return x0 + (i + 0.5) * cell; }
  double cy(int j) const { return y0 + (j + 0.5) * cell; }
};

CoverageGrid coverage_build_grid(const TestPatternSet& s, const machine::MachineProfile& p) {
  const double w = p.print.line_width_mm;
  if (!(w > 0)) throw InputError("the profile's line width must be positive");
  if (s.pads < 0 || s.line_steps < 0 || s.rings < 0) throw InputError("pattern counts must not be negative");
  // Rows: pads, then line steps, then rings, each row's items side by side.
  const double pads_w = s.pads * s.pad_mm + std::max(0, s.pads - 1) * s.spacing_mm;
  const double lines_h = s.line_steps * s.spacing_mm;
  const double ring_d = 2 * s.ring_radius_mm + 2 * w;
  const double rings_w = s.rings * ring_d + std::max(0, s.rings - 1) * s.spacing_mm;
  const double width = std::max({pads_w, s.line_steps > 0 ? s.line_mm : 0.0, rings_w});
  const double height = (s.pads > 0 ? s.pad_mm + s.spacing_mm : 0) + (s.line_steps > 0 ? lines_h + s.spacing_mm : 0) +
                        (s.rings > 0 ? ring_d : 0);
  const auto& ax = p.axis("x");
  const auto& ay = p.axis("y");
  constexpr double kMargin = 5;
  if (width > ax.max_mm - ax.min_mm - 2 * kMargin || height > ay.max_mm - ay.min_mm - 2 * kMargin)
    throw InputError(
        fmt::format("the test patterns ({:.0f} x {:.0f} mm) do not fit the bed ({:.0f} x {:.0f} mm less "
                    "{:g} mm margins)",
                    width, height, ax.max_mm - ax.min_mm, ay.max_mm - ay.min_mm, kMargin));
  CoverageGrid g;
  g.cell = w;
  g.nx = static_cast<int>(std::ceil(width / w));
  g.ny = static_cast<int>(std::ceil(height / w));
  g.x0 = 0.5 * (ax.min_mm + ax.max_mm) - 0.5 * g.nx * w;
  g.y0 = 0.5 * (ay.min_mm + ay.max_mm) - 0.5 * g.ny * w;
  g.print.assign(static_cast<std::size_t>(g.nx * g.ny), 0);
  auto set_cell = [&](double x, double y) {  // local mm from the grid origin
    const int i = static_cast<int>(std::floor(x / w)), j = static_cast<int>(std::floor(y / w));
    if (g.inside(i, j)) g.print[static_cast<std::size_t>(j * g.nx + i)] = 1;
  };
  double y = 0;
  if (s.pads > 0) {
    for (int k = 0; k < s.pads; ++k)
      for (double px = 0; px < s.pad_mm; px += w)
        for (double py = 0; py < s.pad_mm; py += w)
          set_cell(k * (s.pad_mm + s.spacing_mm) + px + 0.5 * w, y + py + 0.5 * w);
    y += s.pad_mm + s.spacing_mm;
  }
  if (s.line_steps > 0) {
    for (int k = 0; k < s.line_steps; ++k) {
      const double len = s.line_mm * (k + 1) / s.line_steps;
      for (double px = 0; px < len; px += w) set_cell(px + 0.5 * w, y + k * s.spacing_mm + 0.5 * w);
    }
    y += lines_h + s.spacing_mm;
  }
  for (int k = 0; k < s.rings; ++k) {
    const double cx = k * (ring_d + s.spacing_mm) + 0.5 * ring_d, cy = y + 0.5 * ring_d;
    for (double px = cx - 0.5 * ring_d; px < cx + 0.5 * ring_d; px += w)
      for (double py = cy - 0.5 * ring_d; py < cy + 0.5 * ring_d; py += w) {
        const double r = std::hypot(px + 0.5 * w - cx, py + 0.5 * w - cy);
        if (r >= s.ring_radius_mm - w && r < s.ring_radius_mm + w) set_cell(px + 0.5 * w, py + 0.5 * w);
      }
  }
  return g;
}

// Cell visiting orders; a jump (not an 8-neighbour step) becomes a travel.
std::vector<std::pair<int, int>> coverage_order_zigzag(const CoverageGrid& g) {
  std::vector<std::pair<int, int>> out;
  for (int j = 0; j < g.ny; ++j)
    for (int i = 0; i < g.nx; ++i)
      if (g.printable(i, j)) out.push_back({i, j});
  return out;
}

std::vector<std::pair<int, int>> coverage_order_pce(const CoverageGrid& g) {
  // Cells still to print, on the grid with a border of one cell that is never open: the open
  // test is one load, and neighbours are index offsets with no bounds checks (the planner runs
  // on every test-pattern protocol the gate sees).
  const std::ptrdiff_t px = g.nx + 2;
  const std::size_t padded = static_cast<std::size_t>(px) * static_cast<std::size_t>(g.ny + 2);
  auto at = [&](int i, int j) { return static_cast<std::size_t>((j + 1) * px + (i + 1)); };
  std::vector<unsigned char> open_cells(padded, 0);
  for (int j = 0; j < g.ny; ++j)
    for (int i = 0; i < g.nx; ++i) open_cells[at(i, j)] = g.print[static_cast<std::size_t>(j * g.nx + i)] != 0;
  // The 8 neighbours in the planner's order: +x, +y, -x, -y, then the diagonals.
  const std::ptrdiff_t step[8] = {1, px, -1, -px, px + 1, px - 1, -px - 1, -px + 1};
  // Neighbours that are not open (covered, not to print, or off the grid): PCE's cost.
  auto cost = [&](std::size_t k) {
    const unsigned char* c = &open_cells[k];
    return 8 - (c[-px - 1] + c[-px] + c[-px + 1] + c[-1] + c[1] + c[px - 1] + c[px] + c[px + 1]);
  };
  std::size_t remaining = static_cast<std::size_t>(std::count(g.print.begin(), g.print.end(), 1));
  std::vector<std::pair<int, int>> out;
  out.reserve(remaining);
  std::size_t cur = 0;
  for (int j = 0; j < g.ny && cur == 0; ++j)
    for (int i = 0; i < g.nx; ++i)
      if (g.printable(i, j)) {
        cur = at(i, j);
        break;
      }
  // The search's marks: a cell is seen in the current search when its mark is >= the search's
  // stamp; the border's mark is the largest, so the search never leaves the grid.
  std::vector<int> seen(padded, std::numeric_limits<int>::max());
  for (int j = 0; j < g.ny; ++j)
    for (int i = 0; i < g.nx; ++i) seen[at(i, j)] = -1;
  std::vector<std::size_t> queue;  // the search's queue, reused
  queue.reserve(padded);
  int stamp = 0;
  while (remaining > 0 && cur != 0) {
    open_cells[cur] = 0;
    out.push_back({static_cast<int>(static_cast<std::ptrdiff_t>(cur) % px) - 1,
                   static_cast<int>(static_cast<std::ptrdiff_t>(cur) / px) - 1});
    --remaining;
    if (remaining == 0) break;
    int best = -1;
    std::size_t next = 0;
    for (const auto d : step) {
      const std::size_t n = static_cast<std::size_t>(static_cast<std::ptrdiff_t>(cur) + d);
      if (!open_cells[n]) continue;
      const int c = cost(n);
      if (c > best) {
        best = c;
        next = n;
      }
    }
    if (best >= 0) {
      cur = next;
      continue;
    }
    // Singularity: breadth-first search for the nearest uncovered cell (Chebyshev steps over the grid).
    ++stamp;
    queue.assign(1, cur);
    seen[cur] = stamp;
    cur = 0;
    for (std::size_t head = 0; head < queue.size(); ++head) {
      const std::size_t k = queue[head];
      if (open_cells[k]) {
        cur = k;
        break;
      }
      for (const auto d : step) {
        const std::size_t n = static_cast<std::size_t>(static_cast<std::ptrdiff_t>(k) + d);
        if (seen[n] >= stamp) continue;
        seen[n] = stamp;
        queue.push_back(n);
      }
    }
  }
  return out;
}

}  // namespace

CoveragePlan plan_test_patterns(const TestPatternSet& set, const machine::MachineProfile& profile,
                                const std::string& planner, const CoverageMotion& motion) {
  if (planner != "pce" && planner != "zigzag")
    throw InputError(fmt::format("unknown planner '{}' (pce, zigzag)", planner));
  const CoverageGrid g = coverage_build_grid(set, profile);
  const auto order = planner == "pce" ? coverage_order_pce(g) : coverage_order_zigzag(g);
  CoveragePlan plan;
  plan.planner = planner;
  plan.cell_mm = g.cell;
  if (order.empty()) throw InputError("the test pattern set has no cell to print");
  // Moves between consecutive cells; collinear extrusions are merged into one move.
  double px = g.cx(order[0].first), py = g.cy(order[0].second);
  int last_di = 0, last_dj = 0;
  for (std::size_t k = 1; k < order.size(); ++k) {
    const int di = order[k].first - order[k - 1].first, dj = order[k].second - order[k - 1].second;
    const bool adjacent = std::abs(di) <= 1 && std::abs(dj) <= 1;
    const double nx = g.cx(order[k].first), ny = g.cy(order[k].second);
    if (adjacent && !plan.moves.empty() && plan.moves.back().extrude && di == last_di && dj == last_dj) {
      plan.moves.back().x1 = nx;
      plan.moves.back().y1 = ny;
    } else {
      plan.moves.push_back({px, py, nx, ny, adjacent});
    }
    last_di = adjacent ? di : 0;
    last_dj = adjacent ? dj : 0;
    px = nx;
    py = ny;
  }
  const double jerk = 1e8;
  for (const auto& m : plan.moves) {
    const double len = std::hypot(m.x1 - m.x0, m.y1 - m.y0);
    const double v = m.extrude ? motion.print_speed_mm_s : motion.travel_speed_mm_s;
    plan.stats.time_s += machine::Profile::move_duration_s(len, 0, v, 0, motion.accel_mm_s2, jerk);
    if (m.extrude) plan.stats.print_mm += len;
    else {
      plan.stats.travel_mm += len;
      ++plan.stats.retractions;
      plan.stats.time_s += 2 * motion.retract_mm / motion.retract_speed_mm_s;
    }
  }
  return plan;
}

}  // namespace tunekit::protocols
