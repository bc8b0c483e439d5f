// FrameTracer::antialias: the rendering options of Antialiasing.h applied to traced centre rays.
#include "FrameTracer.h"

#include "PixelLookup.h"

#include <omp.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <functional>
#include <string>
#include <tuple>

namespace asrt
{
namespace
{
/// The footprint of a record's pixel, scaled to a cell of 1/n of its side; non-finite entries
/// where the record's Jacobian is undefined.
TextureFootprint footprintOf(const RayRecord& r, int n)
{
  const double s = 1.0 / n;
  return { s * r.dudi, s * r.dvdi, s * r.dudj, s * r.dvdj };
}

bool hasFootprint(const RayRecord& r)
{
  return std::isfinite(r.dudi) && std::isfinite(r.dudj) && std::isfinite(r.dvdi) &&
         std::isfinite(r.dvdj);
}

/// How far the neighbour at pixel offset (di, dj) lies from where the record's footprint puts it,
/// in pixels: the footprint is the linearisation of the screen-to-surface map, and where the map
/// bends within a pixel the filter averages over the wrong patch. Infinite if the footprint is
/// singular.
double footprintMisfit(const RayRecord& r, const JacobianSample& s, int di, int dj)
{
  const double a = r.dudi, b = r.dudj, c = r.dvdi, d = r.dvdj;
  const double det = a * d - b * c;
  const double scale = std::max({ std::abs(a), std::abs(b), std::abs(c), std::abs(d) });
  if (!(std::abs(det) > 1e-12 * scale * scale))
    return std::numeric_limits<double>::infinity();
  const double du = shortUDifference(s.u, r.u) - (a * di + b * dj);
  const double dv = (s.v - r.v) - (c * di + d * dj);
  const double x = (d * du - b * dv) / det, y = (-c * du + a * dv) / det;
  // Not std::hypot: this runs for every pixel's 4 neighbours, and its guard against overflow
  // costs several times the square root (an overflow gives infinity, a misfit all the same).
  return std::sqrt(x * x + y * y);
}

/// Where sample (a, b) of a pixel's n × n pattern lies, from the pixel's centre: the square grid
/// rotated by atan(1/n), x = (n·a + b + ½)/n² − ½, y = (n·b + n − 1 − a + ½)/n² − ½. Each of the
/// n × n cells of the pixel holds one sample, as in a stratified grid, and besides every one of
/// the n² columns and the n² rows holds one at its middle ("n-rooks"): an edge along a pixel
/// axis, which the plain grid resolves in steps of 1/n of the pixel, is resolved in steps of 1/n².
/// For odd n, sample (⌊n/2⌋, ⌊n/2⌋) is the centre.
std::pair<double, double> sampleOffset(int a, int b, int n)
{
  const double n2 = static_cast<double>(n) * n;
  return { (n * a + b + 0.5) / n2 - 0.5, (n * b + (n - 1 - a) + 0.5) / n2 - 0.5 };
}

IntegratorConfig sampleIntegrator(const IntegratorConfig& frame)
{
  IntegratorConfig c = frame;
  if (c.relativeTolerance < kSampleRelativeTolerance)
  {
    c.absoluteTolerance *= kSampleRelativeTolerance / c.relativeTolerance;
    c.relativeTolerance = kSampleRelativeTolerance;
  }
  return c;
}

/// A neighbour's screen-space misfit above this many pixels marks the footprint as non-linear.
constexpr double kMaxFootprintMisfit = 0.5;

// `sample(a, b, alike)` below is sample (a, b) of a pixel's n × n pattern: its filtered colour;
// `alike` says whether its ray ends as the pixel's centre ray does.

/// The mean of all n × n samples of the pattern.
template<typename PatternSample>
Color fullPattern(int n, const PatternSample& sample)
{
  Color sum = Color::Zero();
  bool alike = false;
  for (int b = 0; b < n; ++b)
    for (int a = 0; a < n; ++a)
      sum += sample(a, b, alike);
  return sum / static_cast<double>(n * n);
}

/// A pixel whose footprint bends, with nothing else to sample it for: the bend shows only where
/// the texture changes across the pixel. The pattern's 4 corner cells (and, for odd n, the
/// centre sample) come first; if their rays end as the centre ray does and their colours spread
/// by at most kSettledColorSpread, their mean is the pixel's colour. Otherwise the other samples
/// are traced too and all n² averaged, as fullPattern does.
template<typename PatternSample>
Color settledByCorners(int n, const PatternSample& sample)
{
  const bool odd = n % 2 == 1;
  // The first samples: the 4 corner cells, then the centre for odd n.
  std::array<std::pair<int, int>, 5> first = {
    { { 0, 0 }, { n - 1, 0 }, { 0, n - 1 }, { n - 1, n - 1 }, { n / 2, n / 2 } }
  };
  const int count = odd ? 5 : 4;
  std::array<Color, 5> taken;
  Color sum = Color::Zero(), lo = Color::Constant(HUGE_VAL), hi = Color::Constant(-HUGE_VAL);
  bool allAlike = true;
  for (int k = 0; k < count; ++k)
  {
    bool alike = false;
    taken[k] = sample(first[k].first, first[k].second, alike);
    allAlike = allAlike && alike;
    sum += taken[k];
    lo = lo.cwiseMin(taken[k]);
    hi = hi.cwiseMax(taken[k]);
  }
  if (allAlike && (hi - lo).maxCoeff() <= kSettledColorSpread)
    return sum / static_cast<double>(count);
  // The whole pattern, summed in fullPattern's order: the colour is fullPattern's, bit for bit.
  Color all = Color::Zero();
  bool alike = false;
  for (int b = 0; b < n; ++b)
    for (int a = 0; a < n; ++a)
    {
      const auto at = std::find(first.begin(), first.begin() + count, std::pair(a, b));
      all += at != first.begin() + count ? taken[at - first.begin()] : sample(a, b, alike);
    }
  return all / static_cast<double>(n * n);
}

/// A bending footprint's second-order picture: the quadratic map of (u, v) over a pixel,
///   u(x, y) = c + a x + b y + d x² + e y² + f x y  (x, y in pixels from the centre),
/// through its centre ray and its 4 edge neighbours' (which every piece of a frame has: a band's
/// halo rows, a subset's halo pixels), and one sample ray off the axes for the cross term f.
/// u is unwrapped the short way about the centre's.
class LocalQuadraticMap
{
public:
  /// False where an edge neighbour is missing (the frame's border) or ends unlike the centre.
  bool fit(const PixelLookup& lookup, const JacobianSample& centre)
  {
    static constexpr int kSteps[4][2] = { { -1, 0 }, { 1, 0 }, { 0, -1 }, { 0, 1 } };
    std::array<JacobianSample, 4> n;
    for (int d = 0; d < 4; ++d)
    {
      const JacobianSample* s = lookup.at(centre.i + kSteps[d][0], centre.j + kSteps[d][1]);
      if (!s || !endsAlike(*s, centre) || !std::isfinite(s->u) || !std::isfinite(s->v))
        return false;
      n[d] = *s;
    }
    this->U0 = centre.u;
    auto set = [&](Coefficients& k, double c, double xm, double xp, double ym, double yp)
    { k = { c, 0.5 * (xp - xm), 0.5 * (yp - ym), 0.5 * (xp + xm) - c, 0.5 * (yp + ym) - c, 0.0 }; };
    auto du = [&](const JacobianSample& s) { return shortUDifference(s.u, centre.u); };
    set(this->U, 0.0, du(n[0]), du(n[1]), du(n[2]), du(n[3]));
    set(this->V, centre.v, n[0].v, n[1].v, n[2].v, n[3].v);
    return true;
  }
  /// Sets the cross terms so that the map passes through (u, v) at (x, y), x y ≠ 0.
  void passThrough(double x, double y, double u, double v)
  {
    this->U[5] = (shortUDifference(u, this->U0) - value(this->U, x, y)) / (x * y);
    this->V[5] = (v - value(this->V, x, y)) / (x * y);
  }
  /// (u, v) at (x, y), u in [0, 1).
  std::pair<double, double> at(double x, double y) const
  {
    const double u = this->U0 + value(this->U, x, y);
    return { u - std::floor(u), value(this->V, x, y) };
  }

private:
  using Coefficients = std::array<double, 6>; // c, a, b, d, e, f
  static double value(const Coefficients& k, double x, double y)
  {
    return k[0] + k[1] * x + k[2] * y + k[3] * x * x + k[4] * y * y + k[5] * x * y;
  }
  double U0 = 0;
  Coefficients U{}, V{};
};

/// How far, in units of a pattern cell's footprint, a traced sample may land from where the local
/// quadratic map puts it for the map to stand in for the pattern's other rays.
constexpr double kQuadraticMisfit = 0.05;
}

void FrameTracer::judgePixels(const std::vector<RayRecord>& records, const PixelLookup& lookup,
                              int adaptiveSide, std::vector<int>& side,
                              std::vector<int>& midpointRays,
                              std::vector<unsigned char>& bendOnly) const
{
  const AntialiasOptions& opts = this->Desc.rendering;
  // Colours lie in [0, 1]: at a threshold of 1 or more colour never decides, and the texture
  // lookups of the pixel and its neighbours are skipped.
  const bool byColor = opts.colorThreshold < 1.0;
  // The 4 edge neighbours: an edge that only a diagonal neighbour sees clips a corner of the
  // pixel, and sampling those pixels too cost a fifth more rays for a tenth of a dB when this
  // judgement was chosen.
  static constexpr int kDirections[4][2] = { { -1, 0 }, { 1, 0 }, { 0, -1 }, { 0, 1 } };

  // 1. Each pixel against its neighbours. A pixel whose footprint is undefined or bends, or
  // whose colour differs, is sampled outright ("hard": kHard, or kBends where the bend is all);
  // a neighbour whose centre ray ends differently marks an edge between the two centres (bit d
  // of `edges`).
  constexpr unsigned char kHard = 1, kBends = 2;
  std::vector<unsigned char> hard(records.size(), 0), edges(records.size(), 0);
  const long recordCount = static_cast<long>(records.size());
#pragma omp parallel for schedule(static) if (recordCount > kParallelRecords)
  for (long k = 0; k < recordCount; ++k)
  {
    const RayRecord& r = records[static_cast<std::size_t>(k)];
    const JacobianSample self = jacobianSample(r);
    const Color c = byColor ? this->pointColor(self) : Color::Zero();
    const bool footprint = r.objectId >= 0 && hasFootprint(r);
    unsigned char h = r.objectId >= 0 && !footprint ? kHard : 0;
    unsigned char e = 0;
    for (int d = 0; d < 4; ++d)
    {
      const int di = kDirections[d][0], dj = kDirections[d][1];
      const JacobianSample* s = lookup.at(r.i + di, r.j + dj);
      if (!s || s->termination == Termination::Running)
        continue;
      if (!endsAlike(*s, self))
        e |= static_cast<unsigned char>(1u << d);
      else if (h != kHard)
      {
        if (byColor && (this->pointColor(*s) - c).cwiseAbs().maxCoeff() > opts.colorThreshold)
          h = kHard;
        else if (footprint && footprintMisfit(r, *s, di, dj) > kMaxFootprintMisfit)
          h = kBends;
      }
    }
    hard[static_cast<std::size_t>(k)] = h;
    edges[static_cast<std::size_t>(k)] = e;
  }

  // 2. The ray through the midpoint of every edge between disagreeing centres, in half-pixel
  // coordinates (2i + di, 2j + dj). An edge's midpoint is traced whether or not its pixels are
  // hard (which a piece cannot tell of a bordering pixel), and counted as a ray of its lower or
  // left pixel: both are properties of the pair, the same in every piece.
  std::vector<std::pair<int, int>> keys;
  for (std::size_t k = 0; k < records.size(); ++k)
    for (int d = 0; d < 4; ++d)
      if (edges[k] & (1u << d))
      {
        keys.emplace_back(2 * records[k].i + kDirections[d][0],
                          2 * records[k].j + kDirections[d][1]);
        midpointRays[k] += kDirections[d][0] + kDirections[d][1] > 0;
      }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  std::vector<JacobianSample> midpoints(keys.size());
  const long keyCount = static_cast<long>(keys.size());
#pragma omp parallel if (keyCount >= kParallelRays)
  {
    std::unique_ptr<Propagator> prop = makePropagator(*this->St, this->Desc.integrator);
#pragma omp for schedule(dynamic, 16)
    for (long q = 0; q < keyCount; ++q)
    {
      const auto [x2, y2] = keys[static_cast<std::size_t>(q)];
      midpoints[static_cast<std::size_t>(q)] =
        jacobianSample(this->traceThrough(*prop, 0.5 * x2, 0.5 * y2));
    }
  }

  // 3. A straight edge crosses the segment between two centres once: where the midpoint ends as
  // the pixel's centre does, the crossing lies in the neighbour's half, and the pixel need not be
  // sampled for it. A midpoint unlike both (a third surface, a thin image) samples both.
#pragma omp parallel for schedule(static) if (recordCount > kParallelRecords)
  for (long q = 0; q < recordCount; ++q)
  {
    const std::size_t k = static_cast<std::size_t>(q);
    bool sample = hard[k] == kHard;
    const JacobianSample self = jacobianSample(records[k]);
    for (int d = 0; d < 4 && !sample; ++d)
      if (edges[k] & (1u << d))
      {
        const std::pair<int, int> key(2 * self.i + kDirections[d][0],
                                      2 * self.j + kDirections[d][1]);
        const auto it = std::lower_bound(keys.begin(), keys.end(), key);
        sample = !endsAlike(midpoints[static_cast<std::size_t>(it - keys.begin())], self);
      }
    if (sample || hard[k] == kBends)
      side[k] = adaptiveSide;
    bendOnly[k] = !sample && hard[k] == kBends;
  }
}

bool FrameTracer::antialias(std::vector<RayRecord>& records,
                            const std::vector<JacobianSample>& neighbours,
                            const std::function<bool(double)>& progress) const
{
  const AntialiasOptions& opts = this->Desc.rendering;
  const bool filter = opts.mode != AntialiasMode::None;
  const Scene& scene = *this->Desc.scene;

  // Which pixels take more rays, and how many a side. The judgement reads only centre rays and
  // the edge midpoints between them, so that it is a function of the frame, not of its pieces.
  const int adaptiveSide = adaptivePatternSide(opts.maxRaysPerPixel);
  std::vector<int> side(records.size(), 1);
  std::vector<int> midpointRays(records.size(), 0);
  std::vector<unsigned char> bendOnly(records.size(), 0);
  // The centre rays and their bordering samples by pixel: for the judgement, and for the local
  // quadratic maps of the footprints it finds bending.
  const bool judged =
    opts.supersample <= 1 && opts.mode == AntialiasMode::Adaptive && adaptiveSide >= 2;
  const PixelLookup lookup = judged ? PixelLookup(records, neighbours) : PixelLookup({}, {});
  if (opts.supersample > 1)
    std::fill(side.begin(), side.end(), opts.supersample);
  else if (judged)
    this->judgePixels(records, lookup, adaptiveSide, side, midpointRays, bendOnly);

  const long recordCount = static_cast<long>(records.size());
#pragma omp parallel for schedule(static) if (recordCount > kParallelRecords)
  for (long q = 0; q < recordCount; ++q)
  {
    // Filtered centre colours (the colour of a pixel left at one ray).
    const std::size_t k = static_cast<std::size_t>(q);
    RayRecord& r = records[k];
    if (filter && side[k] == 1 && r.objectId >= 0 && hasFootprint(r))
      r.color = scene.shadeFootprint(r.objectId, r.u, r.v, footprintOf(r, 1));
    r.raysPerPixel = (r.traced ? 1 : 0) + midpointRays[k];
  }

  std::vector<std::size_t> sampled;
  for (std::size_t k = 0; k < records.size(); ++k)
    if (side[k] > 1)
      sampled.push_back(k);
  if (sampled.empty())
    return true;

  // n² samples on a rotated grid (sampleOffset), each filtered over its share of the footprint
  // (the centre ray's, scaled by 1/n); the box reconstruction averages them. For odd n the middle
  // sample is the pixel's centre and takes the centre ray; for even n the centre ray is not a
  // sample (patternRays). A pixel sampled only because its footprint bends may be settled by
  // the pattern's corner cells (settledByCorners).
  const long count = static_cast<long>(sampled.size());
  std::atomic<long> done{ 0 };
  std::atomic<bool> stop{ false };
  const long reportEvery = std::max(1L, count / 200);
  // A supersample is a reference: its samples are traced as tightly as the frame's centre rays.
  const IntegratorConfig sampling =
    opts.supersample > 1 ? this->Desc.integrator : sampleIntegrator(this->Desc.integrator);
#pragma omp parallel if (count * kRaysPerItem >= kParallelRays)
  {
    std::unique_ptr<Propagator> prop = makePropagator(*this->St, sampling);
    long lastReported = 0;
#pragma omp for schedule(dynamic, 1)
    for (long q = 0; q < count; ++q)
    {
      if (stop.load(std::memory_order_relaxed))
        continue;
      const std::size_t k = sampled[static_cast<std::size_t>(q)];
      RayRecord& r = records[k];
      const int n = side[k];
      const TextureFootprint cell = footprintOf(r, n);
      const bool cellFilter = filter && r.objectId >= 0 && hasFootprint(r);
      int rays = r.traced ? 1 : 0;
      // The pattern's rays traced for the local quadratic map are kept for the pattern, should
      // the map not stand in for it.
      std::array<std::pair<int, int>, 2> keptAt;
      std::array<RayRecord, 2> kept;
      int keptCount = 0;
      auto traced = [&](int a, int b) -> RayRecord
      {
        for (int m = 0; m < keptCount; ++m)
          if (keptAt[m] == std::pair(a, b))
            return kept[m];
        const auto [x, y] = sampleOffset(a, b, n);
        const RayRecord s = this->traceThrough(*prop, r.i + x, r.j + y);
        ++rays;
        if (keptCount < 2)
        {
          keptAt[keptCount] = { a, b };
          kept[keptCount++] = s;
        }
        return s;
      };
      auto colourOf = [&](const RayRecord& s) -> Color
      {
        if (cellFilter && s.objectId == r.objectId && s.imageOrder == r.imageOrder)
          return scene.shadeFootprint(s.objectId, s.u, s.v, cell);
        return s.color;
      };
      // Sample (a, b) of the pattern: its filtered colour, and whether its ray ends as the
      // centre's does.
      auto sample = [&](int a, int b, bool& alike) -> Color
      {
        const RayRecord s = n % 2 == 1 && a == n / 2 && b == n / 2 ? r : traced(a, b);
        alike = endsAlike(jacobianSample(s), jacobianSample(r));
        return colourOf(s);
      };
      // A footprint that bends, seen by the quadratic map through the centre, its edge
      // neighbours and the pattern's first corner: where the opposite corner lands where the map
      // puts it, with the colour it predicts, the map places the pattern's other samples.
      auto byQuadraticMap = [&](Color& colour)
      {
        LocalQuadraticMap map;
        if (!map.fit(lookup, jacobianSample(r)))
          return false;
        const RayRecord first = traced(0, 0), last = traced(n - 1, n - 1);
        if (!endsAlike(jacobianSample(first), jacobianSample(r)) ||
            !endsAlike(jacobianSample(last), jacobianSample(r)))
          return false;
        const auto [x0, y0] = sampleOffset(0, 0, n);
        map.passThrough(x0, y0, first.u, first.v);
        const auto [x1, y1] = sampleOffset(n - 1, n - 1, n);
        RayRecord predicted = r;
        std::tie(predicted.u, predicted.v) = map.at(x1, y1);
        const double allowed =
          kQuadraticMisfit / n * std::max(std::hypot(r.dudi, r.dvdi), std::hypot(r.dudj, r.dvdj));
        if (!(std::abs(shortUDifference(last.u, predicted.u)) <= allowed &&
              std::abs(last.v - predicted.v) <= allowed) ||
            (colourOf(predicted) - colourOf(last)).cwiseAbs().maxCoeff() > kSettledColorSpread)
          return false;
        // Summed in fullPattern's order.
        Color sum = Color::Zero();
        for (int b = 0; b < n; ++b)
          for (int a = 0; a < n; ++a)
          {
            if (a == 0 && b == 0)
              sum += colourOf(first);
            else if (a == n - 1 && b == n - 1)
              sum += colourOf(last);
            else if (n % 2 == 1 && a == n / 2 && b == n / 2)
              sum += colourOf(r);
            else
            {
              const auto [x, y] = sampleOffset(a, b, n);
              std::tie(predicted.u, predicted.v) = map.at(x, y);
              sum += colourOf(predicted);
            }
          }
        colour = sum / static_cast<double>(n * n);
        return true;
      };
      Color colour;
      if (bendOnly[k] && n >= 3 && cellFilter && byQuadraticMap(colour))
        r.color = colour;
      else
        r.color = bendOnly[k] && n >= 3 ? settledByCorners(n, sample) : fullPattern(n, sample);
      r.raysPerPixel = rays + midpointRays[k];
      const long d = ++done;
      if (progress && omp_get_thread_num() == 0 && d - lastReported >= reportEvery)
      {
        lastReported = d;
        if (!progress(static_cast<double>(d) / count))
          stop = true;
      }
    }
  }
  return !stop;
}

namespace
{
/// Throws InvalidParameter unless the whole frame `frame` traced with `from` can be anti-aliased
/// again into `to`'s (FrameTracer::antialiasAgain).
void checkAntialiasAgain(const std::vector<RayRecord>& frame, const AntialiasOptions& from,
                         const AntialiasOptions& to, int width, int height)
{
  const auto refuse = [](const std::string& why)
  { throw InvalidParameter("anti-aliasing a traced frame again: " + why); };
  AntialiasOptions same = from;
  same.maxRaysPerPixel = to.maxRaysPerPixel;
  if (same != to)
    refuse("the renderings differ in more than maxRaysPerPixel");
  if (to.mode != AntialiasMode::Adaptive || to.supersample > 1)
    refuse("the rendering is not adaptive sampling without a supersample");
  if (adaptivePatternSide(from.maxRaysPerPixel) < 2)
    refuse("the frame was traced with maxRaysPerPixel " + std::to_string(from.maxRaysPerPixel) +
           ", which samples no pixel");
  const int side = adaptivePatternSide(to.maxRaysPerPixel);
  if (side < 2 || side % 2 != 0)
    refuse("maxRaysPerPixel " + std::to_string(to.maxRaysPerPixel) + " gives a pattern of side " +
           std::to_string(side) + ", not an even side of 2 or more");
  const std::size_t w = static_cast<std::size_t>(width);
  if (frame.size() != w * static_cast<std::size_t>(height))
    refuse("the frame has " + std::to_string(frame.size()) + " records for " +
           std::to_string(width) + " x " + std::to_string(height) + " pixels");
  for (std::size_t k = 0; k < frame.size(); ++k)
    if (frame[k].i != static_cast<int>(k % w) || frame[k].j != static_cast<int>(k / w))
      refuse("record " + std::to_string(k) + " is not pixel (" + std::to_string(k % w) + ", " +
             std::to_string(k / w) + ")");
}
}

bool FrameTracer::antialiasAgain(std::vector<RayRecord>& frame, const AntialiasOptions& tracedWith,
                                 const std::function<bool(double)>& progress) const
{
  checkAntialiasAgain(frame, tracedWith, this->Desc.rendering, this->Desc.camera.width,
                      this->Desc.camera.height);
  return this->antialias(frame, {}, progress);
}

std::vector<RayRecord> FrameTracer::antialiasAgain(const std::vector<RayRecord>& frame,
                                                   const AntialiasOptions& tracedWith,
                                                   const std::vector<std::int32_t>& pixels) const
{
  const int width = this->Desc.camera.width, height = this->Desc.camera.height;
  checkAntialiasAgain(frame, tracedWith, this->Desc.rendering, width, height);
  std::vector<unsigned char> asked(frame.size(), 0);
  std::vector<RayRecord> records;
  records.reserve(pixels.size());
  for (const std::int32_t p : pixels)
  {
    if (p < 0 || static_cast<std::size_t>(p) >= frame.size())
      throw InvalidParameter("anti-aliasing a traced frame again: pixel index " +
                             std::to_string(p) + " lies outside the frame");
    if (asked[static_cast<std::size_t>(p)]++)
      throw InvalidParameter("anti-aliasing a traced frame again: pixel index " +
                             std::to_string(p) + " is given twice");
    records.push_back(frame[static_cast<std::size_t>(p)]);
  }
  // The judgement and the footprints' quadratic maps read the 4 edge neighbours' centre rays.
  std::vector<std::pair<int, int>> ij;
  ij.reserve(pixels.size());
  for (const RayRecord& r : records)
    ij.emplace_back(r.i, r.j);
  this->antialias(records, edgeNeighbourSamples(frame, width, height, ij));
  return records;
}
}
