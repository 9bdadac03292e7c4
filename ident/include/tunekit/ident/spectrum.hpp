#pragma once
// Welch spectral estimates on FFTW: power spectral density, cross spectral density, and
// the H1 frequency-response estimate H1 = Pxy / Pxx with magnitude-squared coherence
// |Pxy|^2 / (Pxx Pyy). Densities are one-sided and scaled like scipy.signal.welch
// (scaling='density'): a signal in units U gives a PSD in U^2/Hz, and integrating the PSD
// over frequency gives the signal's variance.

#include <complex>
#include <cstddef>
#include <span>
#include <string>
#include <vector>

namespace tunekit::ident {

enum class WindowType { rectangular, hann, hamming, kaiser };
enum class Detrend { none, constant, linear };

/// Parses "hann", "hamming", "kaiser", "rect"/"boxcar"; throws InputError otherwise.
WindowType parse_window(const std::string& name);
std::string to_string(WindowType w);

/// Periodic (DFT-even) window of length n, as scipy.signal.get_window and numpy's
/// kaiser (symmetric) for kaiser: Klipper uses np.kaiser(n, beta), which is symmetric.
std::vector<double> make_window(WindowType type, std::size_t n, double kaiser_beta = 6.0);

struct WelchOptions {
  WindowType window = WindowType::hann;
  double kaiser_beta = 6.0;
  std::size_t segment_length = 0;  ///< samples per segment; 0: 2^ceil(log2(fs * 0.5 s))
  double overlap = 0.5;            ///< fraction of a segment, 0 <= overlap < 1
  Detrend detrend = Detrend::constant;
};

/// Klipper's preset (shaper_calibrate.py): Kaiser beta 6, 2^ceil(log2(fs/2)) samples,
/// 50 % overlap, mean removed per segment.
WelchOptions klipper_welch_options();

struct Spectrum {
  std::vector<double> freq_hz;
  std::vector<double> psd;  ///< U^2/Hz
  std::size_t segments = 0;
  std::size_t segment_length = 0;
  double sample_rate_hz = 0;
};

struct CrossSpectrum {
  std::vector<double> freq_hz;
  std::vector<std::complex<double>> pxy;  ///< conj(X) Y, U_x U_y / Hz
  std::vector<double> pxx, pyy;
  std::size_t segments = 0;
  std::size_t segment_length = 0;
  double sample_rate_hz = 0;
};

struct FrequencyResponse {
  std::vector<double> freq_hz;
  std::vector<std::complex<double>> h;  ///< output / input
  std::vector<double> coherence;        ///< 0..1
  std::size_t segments = 0;
};

/// Resolves segment_length 0 to its default for a sampling rate, and checks the options.
std::size_t resolve_segment_length(const WelchOptions& o, double sample_rate_hz);

/// Magnitude of the DFT of one windowed (Hann), mean-removed record zero-padded to `nfft`
/// points (>= x.size()): bins k = 0..nfft/2 at k * fs / nfft Hz, in U (not a density). For
/// locating peaks of a short record (a ring-down) more finely than its length resolves.
std::vector<double> padded_amplitude_spectrum(std::span<const double> x, std::size_t nfft);

/// Throws InputError when the record is shorter than two segments or options are invalid.
Spectrum welch_psd(std::span<const double> x, double sample_rate_hz, const WelchOptions& options = {});
/// welch_psd of each of several channels of one length (one record's axes), the channels after
/// the first on threads of their own; they share one window and one transform plan.
std::vector<Spectrum> welch_psds(std::span<const std::span<const double>> channels, double sample_rate_hz,
                                 const WelchOptions& options = {});
CrossSpectrum welch_csd(std::span<const double> x, std::span<const double> y, double sample_rate_hz,
                        const WelchOptions& options = {});
/// H1 estimate of the system from input x to output y.
FrequencyResponse h1_estimate(std::span<const double> x, std::span<const double> y, double sample_rate_hz,
                              const WelchOptions& options = {});

}  // namespace tunekit::ident
