// Image quality against a reference: PSNR and SSIM, the standard formulas, for judging
// interpolated frames against traced ones (tests and benchmarks), and Spearman's rank correlation,
// for judging an error estimate against the true error. Plain C++.
#ifndef asrt_ImageQuality_h
#define asrt_ImageQuality_h

#include "asrtInterpolationModule.h"

#include <cstdint>
#include <vector>

namespace asrt
{
/// An 8-bit RGB image, row-major (3 bytes a pixel), and optionally which pixels count.
struct RgbView
{
  int width = 0, height = 0;
  const std::uint8_t* rgb = nullptr;
};

/// Peak signal-to-noise ratio over the three channels: 10 log10(255² / MSE), in dB; infinity for
/// identical images. `mask` (one byte a pixel, non-zero: counts), if given, restricts the pixels.
/// Throws InvalidParameter for images of different sizes or an empty selection.
ASRTINTERPOLATION_EXPORT double psnr(const RgbView& a, const RgbView& b,
                                     const std::vector<std::uint8_t>* mask = nullptr);

/// Mean structural similarity (Wang, Bovik, Sheikh & Simoncelli 2004) of the luma
/// Y = 0.299 R + 0.587 G + 0.114 B: Gaussian window 11 × 11 with σ = 1.5 (normalised),
/// C1 = (0.01 L)², C2 = (0.03 L)², L = 255, over the pixels whose whole window lies inside the
/// image (the paper's "valid" region) and, if given, inside `mask`. 1 for identical images.
ASRTINTERPOLATION_EXPORT double ssim(const RgbView& a, const RgbView& b,
                                     const std::vector<std::uint8_t>* mask = nullptr);

/// Spearman's rank correlation of x and y: Pearson's correlation of their ranks, tied values
/// sharing the mean of their ranks. NaN where either is constant. Throws InvalidParameter for
/// sizes that differ or fewer than 2 values.
ASRTINTERPOLATION_EXPORT double spearman(const std::vector<double>& x,
                                         const std::vector<double>& y);
}

#endif
