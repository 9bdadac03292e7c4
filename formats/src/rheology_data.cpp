#include "tunekit/formats/rheology_data.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/fitting/stats.hpp"
#include "tunekit/formats/csv.hpp"

namespace tunekit::formats {
namespace {

constexpr double kHugeViscosity = 1e300;
// A fall of the shear stress with rising shear rate beyond this fraction draws a warning.
constexpr double kStressDropTolerance = 0.1;

std::string lower_nospace(std::string_view s) {
  std::string o;
  for (char c : s)
    if (c != ' ') o.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(c))));
  return o;
}

// 1-based line numbers of the data rows (the lines after the header that are neither blank
// nor comments), so errors can point at FILE:LINE.
std::vector<std::size_t> data_row_lines(std::string_view text, std::size_t header_line) {
  std::vector<std::size_t> lines;
  std::size_t ln = 0, pos = 0;
  while (pos <= text.size()) {
    const auto nl = text.find('\n', pos);
    std::string_view line = text.substr(pos, nl == std::string_view::npos ? std::string_view::npos : nl - pos);
    ++ln;
    if (ln > header_line) {
      const auto first = line.find_first_not_of(" \t\r");
      if (first != std::string_view::npos && line[first] != '#') lines.push_back(ln);
    }
    if (nl == std::string_view::npos) break;
    pos = nl + 1;
  }
  return lines;
}

// The column named in the options (which must exist), else the first of the usual names.
const CsvColumn* find_column(const CsvTable& t, const std::string& given, std::initializer_list<const char*> names) {
  if (!given.empty()) return &t.column(given);
  for (const char* n : names)
    if (t.has_column(n)) return &t.column(n);
  return nullptr;
}

}  // namespace

double viscosity_unit_factor(std::string_view unit) {
  const auto u = lower_nospace(unit);
  if (u.empty() || u == "pa.s" || u == "pas" || u == "pa*s" || u == "pa_s" || u == "pa\xc2\xb7s") return 1.0;
  if (u == "mpa.s" || u == "mpas" || u == "mpa*s" || u == "mpa_s" || u == "cp") return 1e-3;
  if (u == "kpa.s" || u == "kpas" || u == "kpa*s" || u == "kpa_s") return 1e3;
  if (u == "p" || u == "poise" || u == "dpa.s" || u == "dpas") return 0.1;  // 1 P = 1 dyn s/cm^2 = 0.1 Pa.s
  throw InputError("unknown viscosity unit '" + std::string(unit) + "' (use Pa.s, mPa.s, cP, P (poise) or kPa.s)");
}

double pressure_unit_factor(std::string_view unit) {
  const auto u = lower_nospace(unit);
  if (u.empty() || u == "pa") return 1.0;
  if (u == "kpa") return 1e3;
  if (u == "mpa") return 1e6;
  if (u == "bar") return 1e5;
  throw InputError("unknown pressure unit '" + std::string(unit) + "' (use Pa, kPa, MPa or bar)");
}

namespace {

enum class TUnit { none, degc, kelvin };

/// The temperature column's unit (the stated one, else the column's): degC or K; an empty or
/// unknown unit is an error at the header.
TUnit temperature_unit(const CsvColumn& temp, const RheologyCsvOptions& o, const std::string& where) {
  const std::string& temp_unit = o.temperature_unit.empty() ? temp.unit : o.temperature_unit;
  const auto u = lower_nospace(temp_unit);
  if (u == "degc" || u == "c" ||
      u == "\xc2\xb0"
           "c" ||
      u == "celsius")
    return TUnit::degc;
  if (u == "k" || u == "kelvin") return TUnit::kelvin;
  if (u.empty())
    throw InputError(
        "the temperature column has no unit: write 'temperature (degC)' or 'temperature (K)', or give "
        "--temperature-unit degC|K",
        where);
  throw InputError("unknown temperature unit '" + temp_unit + "' (use degC or K)", where);
}

/// One row's temperature in kelvin, refused where the values look like the other unit.
double row_temperature_K(double v, TUnit tu, double kelvin_offset, const std::string& where) {
  if (tu == TUnit::kelvin) {
    if (v < 273.15)
      throw InputError(fmt::format("temperature {:g} K is below 0 degC; the values look like degC but the "
                                   "column says K (write 'temperature (degC)')",
                                   v),
                       where);
    if (v > 1200) throw InputError(fmt::format("temperature {:g} K is implausible for a polymer melt", v), where);
    return v;
  }
  if (v > 600)
    throw InputError(fmt::format("temperature {:g} degC is above 600 degC; the values look like kelvin but the "
                                 "column says degC (write 'temperature (K)')",
                                 v),
                     where);
  if (v < -50) throw InputError(fmt::format("temperature {:g} degC is implausible for a polymer melt", v), where);
  return v + kelvin_offset;
}

/// The flow curve tau(gamma) = eta gamma rises with the shear rate in every stable melt (a
/// falling one is flow instability or a column mix-up): checked per temperature, located.
template <class At>
void warn_falling_flow_curve(const fitting::RheologyData& d, const std::vector<std::size_t>& kept_row, const At& at,
                             std::vector<std::string>& warnings) {
  for (double T : d.temperature_levels_K()) {
    std::vector<std::pair<double, std::size_t>> at_T;
    for (std::size_t i = 0; i < d.size(); ++i)
      if (std::abs(d.temperature_K[i] - T) <= 0.05 + 1e-9) at_T.push_back({d.shear_rate_1_s[i], i});
    std::sort(at_T.begin(), at_T.end());
    for (std::size_t q = 1; q < at_T.size(); ++q) {
      const auto [g0, i0] = at_T[q - 1];
      const auto [g1, i1] = at_T[q];
      if (!(g1 > g0 * (1 + 1e-9))) continue;
      const double s0 = d.viscosity_Pa_s[i0] * g0, s1 = d.viscosity_Pa_s[i1] * g1;
      if (s1 < s0 * (1 - kStressDropTolerance)) {
        warnings.push_back(
            fmt::format("{}: the shear stress falls from {:g} to {:g} Pa as the shear rate rises from {:g} to {:g} "
                        "1/s at {:g} K; "
                        "a melt's flow curve rises (flow instability, or a column or unit mix-up)",
                        at(kept_row[i1]), s0, s1, g0, g1, T));
        break;
      }
    }
  }
}

// The columns a rheology table reads: shear rate, viscosity or shear stress (or both, then
// compared), and the optional temperature, pressure and weight.
struct RheologyColumns {
  const CsvColumn* g = nullptr;
  const CsvColumn* eta = nullptr;
  const CsvColumn* tau = nullptr;
  const CsvColumn* temp = nullptr;
  const CsvColumn* pres = nullptr;
  const CsvColumn* w = nullptr;
};

// InputError (at the header) when there is no shear-rate column, its unit is not 1/s, or there
// is neither a viscosity nor a shear-stress column.
RheologyColumns rheology_columns(const CsvTable& t, const RheologyCsvOptions& o, const std::string& header_at) {
  RheologyColumns c;
  c.g = find_column(t, o.shear_rate_column, {"shear_rate", "shear rate", "shearrate", "gamma_dot"});
  if (!c.g)
    throw InputError("no shear-rate column: name one 'shear_rate (1/s)' or give it with --shear-rate COL", header_at);
  {
    const auto u = lower_nospace(c.g->unit);
    if (!(u.empty() || u == "1/s" || u == "s^-1" || u == "s-1" || u == "/s"))
      throw InputError("shear rate unit '" + c.g->unit + "' is not 1/s", header_at);
  }
  c.eta = o.stress_column.empty() ? find_column(t, o.viscosity_column, {"viscosity", "eta"}) : nullptr;
  c.tau = o.viscosity_column.empty()
              ? find_column(t, o.stress_column, {"shear_stress", "shear stress", "stress", "tau"})
              : nullptr;
  if (!c.eta && !c.tau)
    throw InputError(
        "no viscosity column: name one 'viscosity (Pa.s)' or 'shear_stress (Pa)', or give it with "
        "--viscosity COL",
        header_at);
  c.temp = find_column(t, o.temperature_column, {"temperature", "temp", "T"});
  c.pres = find_column(t, o.pressure_column, {"pressure", "p"});
  c.w = find_column(t, {}, {"weight"});
  return c;
}

// How the viscosities are read: factors to Pa.s of the viscosity column (vf) or to Pa of the
// shear-stress column (sf), and the viscosity unit as stated (empty: not stated).
struct ViscosityReading {
  double vf = 1.0, sf = 1.0;
  std::string eta_unit;
};

ViscosityReading viscosity_reading(const RheologyColumns& c, const RheologyCsvOptions& o,
                                   std::vector<std::string>& notes, const std::string& header_at) {
  ViscosityReading r;
  if (c.eta) {
    r.eta_unit = c.eta->unit;
    if (!o.viscosity_unit.empty()) {
      const double given = viscosity_unit_factor(o.viscosity_unit);
      if (!c.eta->unit.empty() && viscosity_unit_factor(c.eta->unit) != given)
        throw InputError("the viscosity column says '" + c.eta->unit + "' but the stated viscosity unit is '" +
                             o.viscosity_unit + "'",
                         header_at);
      r.eta_unit = o.viscosity_unit;
    }
    r.vf = viscosity_unit_factor(r.eta_unit);
    if (r.vf != 1.0) notes.push_back(fmt::format("viscosity: {} -> Pa.s (x {:g})", r.eta_unit, r.vf));
    if (r.eta_unit.empty()) notes.push_back("viscosity column has no unit; read as Pa.s");
  } else {
    if (!o.viscosity_unit.empty())
      throw InputError("a viscosity unit was stated but the file has no viscosity column (it has shear_stress)",
                       header_at);
    r.sf = pressure_unit_factor(o.stress_unit.empty() ? c.tau->unit : o.stress_unit);
  }
  return r;
}

// The temperatures selected (degC, both ends included), when a range was given.
struct TemperatureWindow {
  bool select = false;
  double lo = -HUGE_VAL, hi = HUGE_VAL;
};

TemperatureWindow temperature_window(const RheologyCsvOptions& o) {
  TemperatureWindow w;
  w.select = std::isfinite(o.temperature_min_degC) || std::isfinite(o.temperature_max_degC);
  w.lo = std::isfinite(o.temperature_min_degC) ? o.temperature_min_degC : -HUGE_VAL;
  w.hi = std::isfinite(o.temperature_max_degC) ? o.temperature_max_degC : HUGE_VAL;
  if (w.select && !(w.lo <= w.hi))
    throw InputError(fmt::format("the temperature range {:g}..{:g} degC is empty", w.lo, w.hi));
  return w;
}

// Row i's viscosity in Pa.s from the viscosity column, or the shear stress over the shear rate
// gi; with both columns the ratio of stress / (rate viscosity) into stress_ratio. InputError at
// the row for a value that is not positive or not finite.
template <class At>
double row_viscosity(const RheologyColumns& c, const ViscosityReading& vr, std::size_t i, double gi,
                     std::vector<double>& stress_ratio, const At& at) {
  double e = 0;
  if (c.eta) {
    e = c.eta->values[i] * vr.vf;
    if (!(e > 0)) throw InputError(fmt::format("non-positive viscosity {:g}", c.eta->values[i]), at(i));
    if (c.tau && c.tau->values[i] > 0)
      stress_ratio.push_back(c.tau->values[i] * pressure_unit_factor(c.tau->unit) / (gi * e));
  } else {
    const double s = c.tau->values[i] * vr.sf;
    if (!(s > 0)) throw InputError(fmt::format("non-positive shear stress {:g}", c.tau->values[i]), at(i));
    e = s / gi;
  }
  if (!std::isfinite(e)) throw InputError(fmt::format("viscosity {:g} Pa.s is not finite", e), at(i));
  return e;
}

// eta = tau / gamma must hold row by row; a factor between the columns is a unit mix-up.
void check_stress_agrees(std::vector<double> stress_ratio, const std::string& header_at) {
  if (stress_ratio.empty()) return;
  const double r = fitting::median(std::move(stress_ratio));
  if (!(r > 0.8 && r < 1.25))
    throw InputError(
        fmt::format("the viscosity and shear_stress columns disagree: shear_stress / shear_rate is {:.4g} times "
                    "the viscosity (median over the rows); one of their units is wrong",
                    r),
        header_at);
}

// Implausible magnitudes are reported once, at their most extreme row, and let through.
struct ViscosityExtremes {
  double hi = 0, lo = kHugeViscosity;
  std::size_t hi_row = 0, lo_row = 0;
};

template <class At>
void warn_implausible_viscosity(const ViscosityExtremes& x, const RheologyColumns& c, const std::string& eta_unit,
                                const At& at, std::vector<std::string>& warnings) {
  const std::string stated =
      c.eta ? (eta_unit.empty() ? std::string("read as Pa.s, no unit stated") : "stated as " + eta_unit)
            : "from shear_stress / shear_rate";
  if (x.hi > kHighViscosity)
    warnings.push_back(
        fmt::format("{}: viscosity {:g} Pa.s ({}) is above {:g} Pa.s, high for a polymer melt; real for high-Tg "
                    "polymers near their "
                    "processing window or high molecular weights, but a column in mPa.s or P read as Pa.s looks the "
                    "same: check the unit",
                    at(x.hi_row), x.hi, stated, kHighViscosity));
  if (x.lo < kLowViscosity)
    warnings.push_back(
        fmt::format("{}: viscosity {:g} Pa.s ({}) is below {:g} Pa.s, low for a polymer melt; check the unit",
                    at(x.lo_row), x.lo, stated, kLowViscosity));
}

}  // namespace

RheologyTable parse_rheology_csv(std::string_view text, const std::string& path, const RheologyCsvOptions& o) {
  const auto t = parse_csv(text, path);
  const auto lines = data_row_lines(text, t.header_line);
  auto at = [&](std::size_t row) { return row < lines.size() ? source_location(path, lines[row]) : path; };
  RheologyTable out;
  auto& d = out.data;
  const std::string header_at = source_location(path, t.header_line);
  const RheologyColumns c = rheology_columns(t, o, header_at);
  const ViscosityReading vr = viscosity_reading(c, o, out.notes, header_at);
  TUnit tu = TUnit::none;
  if (c.temp) {
    tu = temperature_unit(*c.temp, o, header_at);
    if (tu == TUnit::degc) out.notes.push_back(fmt::format("temperature: degC -> K (+{:g})", o.kelvin_offset));
  } else if (!std::isfinite(o.temperature_degC)) {
    throw InputError("no temperature: add a 'temperature (degC)' or '(K)' column, or give the temperature of the data",
                     path);
  }
  const double pf = c.pres ? pressure_unit_factor(c.pres->unit) : 1.0;
  const TemperatureWindow tw = temperature_window(o);
  ViscosityExtremes x;
  std::size_t skipped = 0;
  // Consistency of a viscosity column with a shear-stress column in the same file.
  std::vector<double> stress_ratio;
  std::vector<std::size_t> kept_row;  // file row of each point kept

  for (std::size_t i = 0; i < t.rows; ++i) {
    const double gi = c.g->values[i];
    if (gi < 0) throw InputError(fmt::format("negative shear rate {:g} 1/s; shear rates must be positive", gi), at(i));
    if (gi == 0) throw InputError("zero shear rate: the fits work on log scales and need shear rates > 0", at(i));
    const double e = row_viscosity(c, vr, i, gi, stress_ratio, at);
    const double TK = c.temp ? row_temperature_K(c.temp->values[i], tu, o.kelvin_offset, at(i))
                             : o.temperature_degC + o.kelvin_offset;
    if (tw.select) {
      const double degc = TK - o.kelvin_offset;
      if (!(degc >= tw.lo - 1e-9 && degc <= tw.hi + 1e-9)) {
        ++skipped;
        continue;
      }
    }
    kept_row.push_back(i);
    if (e > x.hi) x.hi = e, x.hi_row = i;
    if (e < x.lo) x.lo = e, x.lo_row = i;
    d.shear_rate_1_s.push_back(gi);
    d.viscosity_Pa_s.push_back(e);
    d.temperature_K.push_back(TK);
    if (c.pres) d.pressure_Pa.push_back(c.pres->values[i] * pf);
    if (c.w) {
      if (!(c.w->values[i] > 0)) throw InputError("weights must be positive", at(i));
      d.weight.push_back(c.w->values[i]);
    }
  }
  if (d.size() == 0) {
    if (tw.select)
      throw InputError(fmt::format("no data rows at {:g}..{:g} degC ({} rows outside)", tw.lo, tw.hi, skipped), path);
    throw InputError("no data rows", path);
  }
  if (tw.select)
    out.notes.push_back(fmt::format("temperatures {:g}..{:g} degC selected: {} of {} rows kept", tw.lo, tw.hi, d.size(),
                                    d.size() + skipped));
  warn_falling_flow_curve(d, kept_row, at, out.warnings);
  check_stress_agrees(std::move(stress_ratio), header_at);
  warn_implausible_viscosity(x, c, vr.eta_unit, at, out.warnings);
  return out;
}

}  // namespace tunekit::formats
