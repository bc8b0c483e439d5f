#include "ImageQuality.h"

#include "AsrtTypes.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>

namespace asrt
{
namespace
{
void requireSameSize(const RgbView& a, const RgbView& b, const std::vector<std::uint8_t>* mask)
{
  if (a.width != b.width || a.height != b.height || a.width <= 0 || a.height <= 0 || !a.rgb ||
      !b.rgb)
  {
    std::ostringstream os;
    os << "images to compare must be non-empty and of one size, got " << a.width << " x "
       << a.height << " and " << b.width << " x " << b.height;
    throw InvalidParameter(os.str());
  }
  if (mask && mask->size() != static_cast<std::size_t>(a.width) * a.height)
    throw InvalidParameter("the mask must hold one value per pixel");
}

double luma(const std::uint8_t* px)
{
  return 0.299 * px[0] + 0.587 * px[1] + 0.114 * px[2];
}
}

double psnr(const RgbView& a, const RgbView& b, const std::vector<std::uint8_t>* mask)
{
  requireSameSize(a, b, mask);
  const std::size_t n = static_cast<std::size_t>(a.width) * a.height;
  double sum = 0;
  std::size_t count = 0;
  for (std::size_t p = 0; p < n; ++p)
  {
    if (mask && !(*mask)[p])
      continue;
    for (int c = 0; c < 3; ++c)
    {
      const double d = static_cast<double>(a.rgb[3 * p + c]) - b.rgb[3 * p + c];
      sum += d * d;
    }
    count += 3;
  }
  if (count == 0)
    throw InvalidParameter("PSNR over no pixels");
  const double mse = sum / static_cast<double>(count);
  return mse == 0 ? std::numeric_limits<double>::infinity()
                  : 10.0 * std::log10(255.0 * 255.0 / mse);
}

double ssim(const RgbView& a, const RgbView& b, const std::vector<std::uint8_t>* mask)
{
  requireSameSize(a, b, mask);
  constexpr int radius = 5; // 11 × 11
  constexpr double sigma = 1.5, L = 255.0;
  constexpr double C1 = (0.01 * L) * (0.01 * L), C2 = (0.03 * L) * (0.03 * L);
  const int W = a.width, H = a.height;
  if (W < 2 * radius + 1 || H < 2 * radius + 1)
    throw InvalidParameter("SSIM needs images of at least 11 x 11 pixels");
  double g[2 * radius + 1], gsum = 0;
  for (int k = -radius; k <= radius; ++k)
    gsum += g[k + radius] = std::exp(-0.5 * k * k / (sigma * sigma));
  for (double& x : g)
    x /= gsum;
  const std::size_t n = static_cast<std::size_t>(W) * H;
  std::vector<double> x(n), y(n);
  for (std::size_t p = 0; p < n; ++p)
  {
    x[p] = luma(a.rgb + 3 * p);
    y[p] = luma(b.rgb + 3 * p);
  }
  // The five local moments by the separable Gaussian: rows first, then columns ("valid" only).
  const int Wv = W - 2 * radius, Hv = H - 2 * radius;
  std::vector<double> rows(static_cast<std::size_t>(H) * Wv * 5);
  for (int j = 0; j < H; ++j)
    for (int i = 0; i < Wv; ++i)
    {
      double m[5] = { 0, 0, 0, 0, 0 };
      for (int k = 0; k <= 2 * radius; ++k)
      {
        const std::size_t p = static_cast<std::size_t>(j) * W + i + k;
        const double w = g[k];
        m[0] += w * x[p];
        m[1] += w * y[p];
        m[2] += w * x[p] * x[p];
        m[3] += w * y[p] * y[p];
        m[4] += w * x[p] * y[p];
      }
      for (int c = 0; c < 5; ++c)
        rows[(static_cast<std::size_t>(j) * Wv + i) * 5 + c] = m[c];
    }
  double total = 0;
  std::size_t count = 0;
  for (int j = 0; j < Hv; ++j)
    for (int i = 0; i < Wv; ++i)
    {
      if (mask && !(*mask)[static_cast<std::size_t>(j + radius) * W + i + radius])
        continue;
      double m[5] = { 0, 0, 0, 0, 0 };
      for (int k = 0; k <= 2 * radius; ++k)
        for (int c = 0; c < 5; ++c)
          m[c] += g[k] * rows[(static_cast<std::size_t>(j + k) * Wv + i) * 5 + c];
      const double mx = m[0], my = m[1];
      const double vx = m[2] - mx * mx, vy = m[3] - my * my, cxy = m[4] - mx * my;
      total += ((2 * mx * my + C1) * (2 * cxy + C2)) / ((mx * mx + my * my + C1) * (vx + vy + C2));
      ++count;
    }
  if (count == 0)
    throw InvalidParameter("SSIM over no pixels (the mask leaves none in the valid region)");
  return total / static_cast<double>(count);
}

namespace
{
/// Ranks from 1, tied values sharing the mean of their ranks.
std::vector<double> ranksOf(const std::vector<double>& x)
{
  std::vector<std::size_t> order(x.size());
  std::iota(order.begin(), order.end(), std::size_t{ 0 });
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return x[a] < x[b]; });
  std::vector<double> rank(x.size());
  for (std::size_t k = 0; k < order.size();)
  {
    std::size_t end = k + 1;
    while (end < order.size() && x[order[end]] == x[order[k]])
      ++end;
    for (std::size_t m = k; m < end; ++m)
      rank[order[m]] = 0.5 * static_cast<double>(k + 1 + end);
    k = end;
  }
  return rank;
}
}

double spearman(const std::vector<double>& x, const std::vector<double>& y)
{
  if (x.size() != y.size() || x.size() < 2)
    throw InvalidParameter("a rank correlation needs two series of one size, at least 2 values, "
                           "got " +
                           std::to_string(x.size()) + " and " + std::to_string(y.size()));
  const std::vector<double> a = ranksOf(x), b = ranksOf(y);
  const double mean = 0.5 * (static_cast<double>(a.size()) + 1);
  double ab = 0, aa = 0, bb = 0;
  for (std::size_t k = 0; k < a.size(); ++k)
  {
    ab += (a[k] - mean) * (b[k] - mean);
    aa += (a[k] - mean) * (a[k] - mean);
    bb += (b[k] - mean) * (b[k] - mean);
  }
  return aa > 0 && bb > 0 ? ab / std::sqrt(aa * bb) : std::numeric_limits<double>::quiet_NaN();
}
}
