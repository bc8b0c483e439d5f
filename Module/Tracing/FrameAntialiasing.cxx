// FrameTracer::antialias: the rendering options of Antialiasing.h applied to traced centre rays.
#include "FrameTracer.h"

#include "PixelLookup.h"

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <cmath>

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
  // u differences the short way round, as the Jacobians take them.
  const double du = (s.u - r.u) - std::round(s.u - r.u) - (a * di + b * dj);
  const double dv = (s.v - r.v) - (c * di + d * dj);
  const double x = (d * du - b * dv) / det, y = (-c * du + a * dv) / det;
  return std::hypot(x, y);
}

/// A neighbour's screen-space misfit above this many pixels marks the footprint as non-linear.
constexpr double kMaxFootprintMisfit = 0.25;
}

bool FrameTracer::antialias(std::vector<RayRecord>& records,
                            const std::vector<JacobianSample>& neighbours,
                            const std::function<bool(double)>& progress) const
{
  const AntialiasOptions& opts = this->Desc.rendering;
  const bool filter = opts.mode != AntialiasMode::None;
  const Scene& scene = *this->Desc.scene;

  // Which pixels take more rays, and how many a side. The judgement reads only centre rays.
  const int adaptiveSide =
    static_cast<int>(std::floor(std::sqrt(static_cast<double>(opts.maxRaysPerPixel)) + 1e-9));
  std::vector<int> side(records.size(), 1);
  if (opts.supersample > 1)
    std::fill(side.begin(), side.end(), opts.supersample);
  else if (opts.mode == AntialiasMode::Adaptive && adaptiveSide >= 2)
  {
    const PixelLookup lookup(records, neighbours);
#pragma omp parallel for schedule(static)
    for (long k = 0; k < static_cast<long>(records.size()); ++k)
    {
      const RayRecord& r = records[static_cast<std::size_t>(k)];
      const JacobianSample self = jacobianSample(r);
      // Colours lie in [0, 1]: at a threshold of 1 or more colour never decides, and the texture
      // lookups of the pixel and its neighbours are skipped.
      const bool byColor = opts.colorThreshold < 1.0;
      const Color c = byColor ? this->pointColor(self) : Color::Zero();
      const bool footprint = r.objectId >= 0 && hasFootprint(r);
      bool disagree = r.objectId >= 0 && !footprint;
      // The 4 edge neighbours: an edge that only a diagonal neighbour sees clips a corner of the
      // pixel, and sampling those pixels too costs a fifth more rays for a tenth of a dB
      // (bench/REPORT.md).
      for (const auto& [di, dj] :
           { std::pair(-1, 0), std::pair(1, 0), std::pair(0, -1), std::pair(0, 1) })
        if (!disagree)
        {
          const JacobianSample* s = lookup.at(r.i + di, r.j + dj);
          if (!s || s->termination == Termination::Running)
            continue;
          disagree =
            s->objectId != r.objectId || s->imageOrder != r.imageOrder ||
            s->termination != r.termination ||
            (byColor && (this->pointColor(*s) - c).cwiseAbs().maxCoeff() > opts.colorThreshold) ||
            (footprint && footprintMisfit(r, *s, di, dj) > kMaxFootprintMisfit);
        }
      if (disagree)
        side[static_cast<std::size_t>(k)] = adaptiveSide;
    }
  }

  // Filtered centre colours (the colour of a pixel left at one ray).
  if (filter)
    for (std::size_t k = 0; k < records.size(); ++k)
    {
      RayRecord& r = records[k];
      if (side[k] == 1 && r.objectId >= 0 && hasFootprint(r))
        r.color = scene.shadeFootprint(r.objectId, r.u, r.v, footprintOf(r, 1));
    }

  std::vector<std::size_t> sampled;
  for (std::size_t k = 0; k < records.size(); ++k)
    if (side[k] > 1)
      sampled.push_back(k);
  if (sampled.empty())
    return true;

  // n × n cells, each traced through its centre and filtered over its own footprint (the centre
  // ray's, scaled); the box reconstruction averages the cells. The cell (⌊n/2⌋, ⌊n/2⌋) holds the
  // pixel's centre (at its middle for odd n, at its corner for even n) and takes the centre ray
  // for its sample, so that a pixel takes exactly n² rays: any fixed point of a cell stratifies
  // the pixel alike.
  const long count = static_cast<long>(sampled.size());
  std::atomic<long> done{ 0 };
  std::atomic<bool> stop{ false };
  const long reportEvery = std::max(1L, count / 200);
#pragma omp parallel
  {
    std::unique_ptr<Propagator> prop = makePropagator(*this->St, this->Desc.integrator);
    long lastReported = 0;
#pragma omp for schedule(dynamic, 1)
    for (long q = 0; q < count; ++q)
    {
      if (stop.load(std::memory_order_relaxed))
        continue;
      RayRecord& r = records[sampled[static_cast<std::size_t>(q)]];
      const int n = side[sampled[static_cast<std::size_t>(q)]];
      const TextureFootprint cell = footprintOf(r, n);
      const bool cellFilter = filter && r.objectId >= 0 && hasFootprint(r);
      Color sum = Color::Zero();
      int rays = 1;
      for (int b = 0; b < n; ++b)
        for (int a = 0; a < n; ++a)
        {
          const bool middle = a == n / 2 && b == n / 2;
          RayRecord s;
          if (middle)
            s = r;
          else
          {
            s = this->traceThrough(*prop, r.i - 0.5 + (a + 0.5) / n, r.j - 0.5 + (b + 0.5) / n);
            ++rays;
          }
          if (cellFilter && s.objectId == r.objectId && s.imageOrder == r.imageOrder)
            sum += scene.shadeFootprint(s.objectId, s.u, s.v, cell);
          else
            sum += s.color;
        }
      r.color = sum / static_cast<double>(n * n);
      r.raysPerPixel = rays;
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
}
