// The layout of the report's plots, read from the SVG the report embeds: no legend box lies over
// plotted data (its own panel's or a neighbouring panel's), and every legend lies inside the figure.
//
// The figures are drawn by PLplot's cairo SVG device, which writes every stroke as a <path> (with a
// y-flipping transform) in its colour and every glyph as a <use> of a glyph <symbol>. A legend is
// the one kind of element painted with a white fill (the page background is a <rect>); the legend's
// own frame, sample lines and labels follow it in the file and lie inside it. Everything else drawn
// in a colour other than the axes' grey and the white background is data (curves, points, markers).
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "test_support.hpp"

namespace {

struct Box {
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  void add(double x, double y) {
    x0 = std::min(x0, x);
    y0 = std::min(y0, y);
    x1 = std::max(x1, x);
    y1 = std::max(y1, y);
  }
  bool valid() const { return x0 <= x1 && y0 <= y1; }
  bool contains(const Box& b, double tol) const {
    return b.x0 >= x0 - tol && b.x1 <= x1 + tol && b.y0 >= y0 - tol && b.y1 <= y1 + tol;
  }
  bool overlaps(const Box& b) const { return b.x0 < x1 && b.x1 > x0 && b.y0 < y1 && b.y1 > y0; }
};

struct Element {
  std::string color;                            // "rgb(..)" of its stroke or fill
  std::vector<std::array<double, 4>> segments;  // drawn segments (page coordinates, pt)
  Box box;                                      // its extent
  bool glyph = false;                           // a text glyph: its box is what it covers
  bool legend_background = false;               // a white-filled area: a legend's box
};

const std::string kAxisGrey = "rgb(15.686275%,15.686275%,15.686275%)";
const std::string kWhite = "rgb(100%,100%,100%)";

std::string attr(const std::string& tag, const std::string& name) {
  const auto p = tag.find(" " + name + "=\"");
  if (p == std::string::npos) return "";
  const auto b = p + name.size() + 3;
  return tag.substr(b, tag.find('"', b) - b);
}

std::string style_value(const std::string& style, const std::string& key) {
  const auto p = style.find(key + ":");
  if (p == std::string::npos || (p > 0 && style[p - 1] != ';')) return "";
  const auto b = p + key.size() + 1;
  return style.substr(b, style.find(';', b) - b);
}

// The coordinate pairs of a path's d (cairo writes absolute M, L, C and Z), as polylines.
std::vector<std::vector<std::pair<double, double>>> path_points(const std::string& d, const std::array<double, 6>& m) {
  std::vector<std::vector<std::pair<double, double>>> lines;
  std::vector<double> nums;
  auto flush = [&] {
    for (std::size_t i = 0; i + 1 < nums.size(); i += 2)
      lines.back().push_back({m[0] * nums[i] + m[2] * nums[i + 1] + m[4], m[1] * nums[i] + m[3] * nums[i + 1] + m[5]});
    nums.clear();
  };
  std::size_t i = 0;
  while (i < d.size()) {
    const char c = d[i];
    if (c == 'M') {
      flush();
      lines.emplace_back();
      ++i;
    } else if (c == 'Z') {
      flush();
      if (!lines.empty() && !lines.back().empty()) lines.back().push_back(lines.back().front());
      ++i;
    } else if (std::isalpha(static_cast<unsigned char>(c))) {
      flush();
      ++i;
    } else if (c == ' ' || c == ',') {
      ++i;
    } else {
      std::size_t used = 0;
      nums.push_back(std::stod(d.substr(i, 32), &used));
      i += used;
    }
  }
  flush();
  return lines;
}

std::array<double, 6> transform_of(const std::string& tag) {
  const std::string t = attr(tag, "transform");
  std::array<double, 6> m{1, 0, 0, 1, 0, 0};
  if (t.rfind("matrix(", 0) == 0) {
    std::string inner = t.substr(7, t.size() - 8);
    std::replace(inner.begin(), inner.end(), ',', ' ');
    std::istringstream in(inner);
    for (auto& v : m) in >> v;
  }
  return m;
}

struct Svg {
  double width = 0, height = 0;
  std::vector<Element> elements;  // in drawing order
};

Svg parse_svg(const std::string& svg) {
  Svg out;
  std::map<std::string, Box> glyphs;  // glyph symbol id -> extent relative to its origin
  std::vector<std::string> group_fill;
  std::string symbol;
  for (std::size_t p = svg.find('<'); p != std::string::npos; p = svg.find('<', p + 1)) {
    const std::string tag = svg.substr(p, svg.find('>', p) - p + 1);
    if (tag.rfind("<svg", 0) == 0) {
      std::istringstream vb(attr(tag, "viewBox"));
      double x = 0, y = 0;
      vb >> x >> y >> out.width >> out.height;
    } else if (tag.rfind("<symbol", 0) == 0) {
      symbol = attr(tag, "id");
    } else if (tag.rfind("</symbol", 0) == 0) {
      symbol.clear();
    } else if (tag.rfind("<g", 0) == 0 && tag.rfind("<g>", 0) != 0) {
      group_fill.push_back(style_value(attr(tag, "style"), "fill"));
    } else if (tag.rfind("<g>", 0) == 0) {
      group_fill.emplace_back();
    } else if (tag.rfind("</g", 0) == 0) {
      if (!group_fill.empty()) group_fill.pop_back();
    } else if (tag.rfind("<path", 0) == 0) {
      const auto lines = path_points(attr(tag, "d"), transform_of(tag));
      if (!symbol.empty()) {
        for (const auto& l : lines)
          for (const auto& [x, y] : l) glyphs[symbol].add(x, y);
        continue;
      }
      const std::string style = attr(tag, "style");
      Element e;
      const std::string fill = style_value(style, "fill"), stroke = style_value(style, "stroke");
      e.legend_background = fill == kWhite;
      e.color = fill.rfind("rgb(", 0) == 0 ? fill : stroke;
      for (const auto& l : lines) {
        for (std::size_t k = 0; k < l.size(); ++k) {
          e.box.add(l[k].first, l[k].second);
          if (k > 0) e.segments.push_back({l[k - 1].first, l[k - 1].second, l[k].first, l[k].second});
        }
      }
      if (e.box.valid()) out.elements.push_back(e);
    } else if (tag.rfind("<use", 0) == 0) {
      const auto g = glyphs.find(attr(tag, "xlink:href").substr(1));
      if (g == glyphs.end() || !g->second.valid()) continue;  // a blank (space)
      const double x = std::stod(attr(tag, "x")), y = std::stod(attr(tag, "y"));
      Element e;
      e.glyph = true;
      e.color = group_fill.empty() ? "" : group_fill.back();
      e.box = {g->second.x0 + x, g->second.y0 + y, g->second.x1 + x, g->second.y1 + y};
      out.elements.push_back(e);
    }
  }
  return out;
}

bool is_data(const Element& e) { return !e.legend_background && e.color != kAxisGrey && e.color != kWhite; }

// Whether segment (x0,y0)-(x1,y1) passes through the open box b (Liang-Barsky clipping).
bool segment_enters(const std::array<double, 4>& s, const Box& b) {
  double t0 = 0, t1 = 1;
  const double dx = s[2] - s[0], dy = s[3] - s[1];
  const std::array<std::pair<double, double>, 4> pq{
      {{-dx, s[0] - b.x0}, {dx, b.x1 - s[0]}, {-dy, s[1] - b.y0}, {dy, b.y1 - s[1]}}};
  for (const auto& [pk, qk] : pq) {
    if (pk == 0) {
      if (qk <= 0) return false;
    } else {
      const double r = qk / pk;
      if (pk < 0) t0 = std::max(t0, r);
      else t1 = std::min(t1, r);
    }
  }
  return t0 < t1;
}

// The SVG documents of the report's figures, by figure id (the line-width photo is a PNG).
std::map<std::string, std::string> embedded_svgs(const std::string& html) {
  std::map<std::string, std::string> out;
  const std::regex figure("<figure id=\"plot-([^\"]+)\"><img alt=\"[^\"]*\" src=\"data:image/svg\\+xml;base64,");
  for (auto it = std::sregex_iterator(html.begin(), html.end(), figure); it != std::sregex_iterator(); ++it) {
    const auto begin = static_cast<std::size_t>(it->position(0) + it->length(0));
    const std::string b64 = html.substr(begin, html.find('"', begin) - begin);
    std::string bytes;
    int value = 0, bits = 0;
    for (char c : b64) {
      const auto k = std::string("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/").find(c);
      if (k == std::string::npos) break;  // '=' padding
      value = (value << 6) | static_cast<int>(k);
      bits += 6;
      if (bits >= 8) {
        bits -= 8;
        bytes.push_back(static_cast<char>((value >> bits) & 0xff));
      }
    }
    out[(*it)[1].str()] = bytes;
  }
  return out;
}

}  // namespace

TEST_CASE("no legend in the calibration report's plots lies over plotted data or beyond the figure") {
  const auto& run = tunekit::test::default_calibration();  // shared, read only
  INFO(run.cli.err);
  REQUIRE(run.cli.code == 0);
  const auto svgs = embedded_svgs(tunekit::test::read_text(run.dir + "/report.html"));
  REQUIRE(svgs.size() >= 3);  // step response, Bode plot and at least one axis's PSD
  int legends = 0;
  for (const auto& [id, text] : svgs) {
    INFO("plot " << id);
    const Svg svg = parse_svg(text);
    REQUIRE(svg.width > 0);
    const auto& el = svg.elements;
    CHECK(std::count_if(el.begin(), el.end(), is_data) > 0);
    for (std::size_t i = 0; i < el.size(); ++i) {
      if (!el[i].legend_background) continue;
      ++legends;
      const Box& lb = el[i].box;
      INFO("legend box x " << lb.x0 << ".." << lb.x1 << ", y " << lb.y0 << ".." << lb.y1 << " (pt)");
      CHECK(lb.x0 >= 0.5);
      CHECK(lb.y0 >= 0.5);
      CHECK(lb.x1 <= svg.width - 0.5);
      CHECK(lb.y1 <= svg.height - 0.5);
      // The legend's own frame, samples and labels: the run of elements after it inside it.
      std::size_t end = i + 1;
      while (end < el.size() && !el[end].legend_background && lb.contains(el[end].box, 0.5)) ++end;
      CHECK(end - i >= 3);  // at least its frame, one sample and one label
      const Box inner{lb.x0 + 0.75, lb.y0 + 0.75, lb.x1 - 0.75, lb.y1 - 0.75};
      int over = 0;
      for (std::size_t k = 0; k < el.size(); ++k) {
        if ((k >= i && k < end) || !is_data(el[k])) continue;
        const bool hit = el[k].glyph ? inner.overlaps(el[k].box)
                                     : std::any_of(el[k].segments.begin(), el[k].segments.end(),
                                                   [&](const auto& s) { return segment_enters(s, inner); });
        if (hit) ++over;
      }
      CHECK(over == 0);  // data elements (curves, points, markers, labels) under or over the legend
    }
  }
  CHECK(legends >= 3);
}
