#pragma once
// Axis resonances from accelerometer data:
//   accelerometer CSV -> sampling and saturation checks -> Welch PSD (per channel, summed as
//   Klipper does) and, with a commanded-acceleration channel, the H1 frequency response and
//   coherence -> peak detection (half-power bandwidth start values) -> modal fit with 95 %
//   intervals (fitting/modal_fit.hpp).
//
// Inputs:
//   * Klipper raw accelerometer CSV: `#time,accel_x,accel_y,accel_z` (s, mm/s^2). Klipper names
//     them raw_data_<axis>_<name>.csv; the axis comes from that name or from options.axis.
//   * Klipper spectrum files (`freq,psd_x,psd_y,psd_z,psd_xyz`, resonances_<axis>_*.csv and
//     calibration_data_<axis>_*.csv): klipper_spectrum.hpp.
//   * Generic CSV with a time column and named acceleration columns (mm/s^2).

#include <complex>
#include <optional>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "tunekit/fitting/modal_fit.hpp"
#include "tunekit/ident/spectrum.hpp"

namespace tunekit::ident {

/// 'x', 'y' or 'z' from a Klipper file name (raw_data_x_..., calibration_data_y_...,
/// resonances_z_...), or 0 when the name does not tell.
char axis_from_filename(const std::string& path);

struct AccelInputOptions {
  std::string time_column = "time";
  std::vector<std::string> accel_columns;  ///< empty: accel_x, accel_y, accel_z
  std::string excitation_column;           ///< commanded acceleration (mm/s^2), optional
  char axis = 0;                           ///< 0: from the file name
  double full_scale_mm_s2 = 0;             ///< sensor range; 0: detect flat-topped extremes
  double max_clipped_fraction = 0.01;      ///< more clipped samples than this: refuse
  double max_gap_s = 0.1;                  ///< a longer hole in the time column: refuse
  double max_missing_fraction = 0.01;      ///< more missing samples than this: refuse
  double max_jitter = 0.02;                ///< relative std. dev. of intervals before resampling
  /// Samples beyond what an accelerometer can report are not measurements (a corrupted line,
  /// a logger fault): up to this fraction of them is replaced by the mean of the neighbouring
  /// good samples, each with a located warning; more is an InputError.
  double max_wild_fraction = 0.001;
};

/// The largest acceleration any supported accelerometer reports, mm/s^2: +-16 g, the widest
/// range of the ADXL345 (Analog Devices, ADXL345 data sheet, Rev. G, 2022), LIS2DW12 and
/// MPU-6050/9250 that Klipper reads (Klipper, docs/Measuring_Resonances.md). A sample beyond it
/// (or beyond twice full_scale_mm_s2 when that is given) is not physical.
inline constexpr double kMaxAccelerometerReading_mm_s2 = 16 * 9806.65;

struct SamplingReport {
  double sample_rate_hz = 0;  ///< 1 / median interval
  double duration_s = 0;
  std::size_t samples = 0;
  double jitter = 0;     ///< std. dev. of intervals / median interval (gaps excluded)
  std::size_t gaps = 0;  ///< intervals longer than 1.5 median intervals
  double max_gap_s = 0;
  std::size_t missing_samples = 0;
  bool resampled = false;  ///< linearly interpolated onto a uniform grid
};

struct ClipReport {
  std::string channel;
  std::size_t samples = 0;  ///< samples at the sensor limit
  double limit_mm_s2 = 0;
};

struct AccelRecord {
  std::string path;
  char axis = 0;
  std::vector<std::string> channel_names;
  std::vector<std::vector<double>> channels;  ///< mm/s^2, uniform sampling
  double start_time_s = 0;                    ///< time of the first sample, on the file's clock
  std::vector<double> excitation;             ///< commanded acceleration, empty if none
  std::string excitation_name;
  SamplingReport sampling;
  std::vector<ClipReport> clipping;
  std::vector<std::string> warnings;
};

/// Parses an accelerometer CSV already in memory. InputError (exit 2) for wrong columns,
/// non-monotonic time, all-zero data, too many clipped samples, large gaps; warnings for
/// small problems that were handled (resampling, a few clipped samples).
/// `on_parsed`, when given, is called once the rows are parsed (on both cores for a large file),
/// before the record's checks: a caller's own work on the bytes (a digest) then runs beside the
/// checks instead of competing with the parse.
AccelRecord load_accel_csv(const std::string& path, std::string_view bytes, const AccelInputOptions& options,
                           const std::function<void()>& on_parsed = {});

/// PSDs of one axis: per channel and summed, on one frequency grid.
struct AxisSpectrum {
  char axis = 0;
  std::vector<std::string> files;
  std::vector<double> freq_hz;
  std::vector<double> psd_x, psd_y, psd_z, psd_sum;  ///< (mm/s^2)^2/Hz
  bool klipper_normalized = false;  ///< already divided by f + 0.1 (a Klipper file with shaper columns)
  std::size_t segments = 0, segment_length = 0;
  double sample_rate_hz = 0;
  WelchOptions welch;
  std::optional<FrequencyResponse> frf;  ///< excitation -> axis channel (first file with one)
  std::vector<std::string> warnings;
};

/// Welch PSDs of a record. Channels named like accel_x/accel_y/accel_z fill psd_x/y/z; any
/// other channels only contribute to psd_sum. With an excitation channel, also H1.
AxisSpectrum record_spectrum(const AccelRecord& r, const WelchOptions& welch);
/// Klipper's spectrum files (resonances_*.csv, calibration_data_*.csv): klipper_spectrum.hpp.
/// Averages several spectra of the same axis (interpolated onto the first one's grid).
AxisSpectrum average_spectra(const std::vector<AxisSpectrum>& spectra);

/// Klipper's normalization of a PSD for shaper selection: divided by (f + 0.1 Hz) and, below
/// 10 Hz, multiplied by exp(1 - (10 / (f + 0.1))^2).
std::vector<double> klipper_normalize(const std::vector<double>& freq_hz, const std::vector<double>& psd);

/// Spectral kernel (leakage) of a Welch estimate with this window and segment length at this
/// sampling rate, sampled at `per_bin` points per bin over +-`half_width_bins` bins.
fitting::SpectralKernel welch_kernel(WindowType window, double kaiser_beta, std::size_t segment_length,
                                     double sample_rate_hz, int per_bin = 8, int half_width_bins = 4);

struct Peak {
  double freq_hz = 0;
  double height = 0;           ///< whitened PSD at the peak
  double half_power_zeta = 0;  ///< start value from the half-power bandwidth
};

struct ResonanceOptions {
  double fit_min_hz = 10.0;
  double fit_max_hz = 133.33;  ///< Klipper's default sweep ends at 133.33 Hz
  int max_modes = 3;
  double peak_threshold = 0.05;     ///< peaks below this fraction of the highest are ignored
  double excitation_exponent = -1;  ///< <0: 2 for raw PSDs, 1 for Klipper-normalized ones
  bool use_frf = true;              ///< fit the FRF when there is an excitation channel
  /// Fit the record against its commanded motion (axis_response_fit.hpp) when the motion was
  /// recorded beside it (commanded_motion_<axis>_<tag>.csv beside raw_data_<axis>_<tag>.csv).
  bool use_commanded_motion = true;
  double min_coherence = 0.5;
};

struct AxisModes {
  std::vector<Peak> peaks;
  std::vector<fitting::ModeEstimate> modes;  ///< sorted by frequency
  std::optional<fitting::ModalFit> fit;
  std::string method;  ///< "psd", "frf", or "output_error" (the record against its commanded motion)
  /// The output-error fit that gave `modes` (method "output_error"); `fit` is then the spectrum's
  /// fit, which started it.
  std::optional<fitting::FitResult> time_fit;
  double time_fit_variance_inflation = 1;
  double band_lo_hz = 0, band_hi_hz = 0;
  int dominant = -1;  ///< index into modes of the strongest peak
  std::vector<std::string> warnings;
};

/// Peaks of the whitened PSD psd / f^p in [lo, hi], strongest first, at most max_modes.
std::vector<Peak> find_peaks(const std::vector<double>& freq_hz, const std::vector<double>& psd, double exponent,
                             double lo_hz, double hi_hz, double threshold, int max_modes, double kernel_enbw_hz);

/// Peak detection and modal fit for one axis. No peak: empty modes and a warning.
AxisModes identify_modes(const AxisSpectrum& s, const ResonanceOptions& options);

}  // namespace tunekit::ident
