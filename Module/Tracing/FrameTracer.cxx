#include "FrameTracer.h"

#include "PixelLookup.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace asrt
{
namespace
{
double angleBetween(const Vec3& a, const Vec3& b)
{
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

}

FrameTracer::FrameTracer(const SceneDescription& scene)
  : Desc(scene)
  , St(makeSpacetime(scene.spacetime))
  , Tracing(scene.tracing)
{
  this->Cam = std::make_unique<Camera>(*this->St, scene.camera);
  // The description says which method actually traces: stored frames are identified by it.
  if (this->Desc.integrator.method == "auto")
    this->Desc.integrator.method = defaultMethod(*this->St);
  makePropagator(*this->St, scene.integrator); // validates method and step before any tracing
  if (!scene.scene)
    throw InvalidParameter("scene has no objects container");
  // Rays must be able to reach the sky before they count as escaped.
  this->Tracing.escapeRadius =
    std::max(this->Tracing.escapeRadius, 1.001 * scene.scene->celestialRadius());
  // Beyond every object but the sky, propagators that can may run in one segment.
  this->Tracing.farField = scene.scene->farField();
}

FrameTracer::~FrameTracer() = default;

void FrameTracer::setFarField(bool enabled)
{
  this->Tracing.farField = enabled ? this->Desc.scene->farField() : FarField{};
}

namespace
{
RayRecord traceWith(const FrameTracer& tracer, Propagator& prop, const TraceOptions& opts, double x,
                    double y, std::vector<PathPoint>* path)
{
  const Spacetime& st = tracer.spacetime();
  const Scene& scene = *tracer.description().scene;
  RayRecord rec;
  rec.i = static_cast<std::int32_t>(std::lround(x));
  rec.j = static_cast<std::int32_t>(std::lround(y));
  const PhasePoint z = tracer.camera().pixelRay(x, y);
  rec.origin = z.x.tail<3>();
  rec.direction = tracer.camera().localDirection(x, y);
  rec.momentum = z.p;

  SurfaceHit hit;
  Segment hitSegment;
  bool found = false;
  auto visitor = [&](const Segment& seg)
  {
    if (path)
      path->push_back(
        { seg.x0.tail<3>(), seg.lambda0, st.radius(seg.x0), std::abs(st.value(seg.x0, seg.p0)) });
    if (scene.firstHit(seg, hit))
    {
      found = true;
      hitSegment = seg;
      return true;
    }
    return false;
  };
  // A path is drawn from the segments' starts: it is to follow the ray all the way out.
  TraceOptions pathOptions;
  if (path)
  {
    pathOptions = opts;
    pathOptions.farField = FarField{};
  }
  const TraceResult res = traceRay(st, prop, z, path ? pathOptions : opts, visitor);
  rec.termination = res.termination;
  rec.steps = res.steps;
  rec.maxAbsH = res.maxAbsH;
  rec.winding = res.winding;
  rec.affineLength = res.affineLength;
  if (found)
  {
    // The tracer counted the whole last step; keep only the part up to the hit.
    const Vec3 a = hitSegment.x0.tail<3>();
    rec.winding += angleBetween(a, hit.point) - angleBetween(a, hitSegment.x1.tail<3>());
    rec.affineLength = hitSegment.lambda(hit.tau);
    rec.objectId = hit.objectId;
    rec.hitPoint = hit.point;
    rec.hitNormal = hit.normal;
    rec.u = hit.u;
    rec.v = hit.v;
    rec.chordError = (hit.chordPoint - hit.point).norm();
    rec.color = scene.shade(hit);
  }
  else
  {
    rec.hitPoint = res.final.x.tail<3>();
    rec.color = scene.endColor(res.termination);
  }
  rec.imageOrder = static_cast<std::int32_t>(std::floor(rec.winding / M_PI));
  if (path)
  {
    const Vec4 endX =
      found ? Vec4(0.0, rec.hitPoint.x(), rec.hitPoint.y(), rec.hitPoint.z()) : res.final.x;
    path->push_back({ endX.tail<3>(), rec.affineLength, st.radius(endX),
                      std::abs(st.value(res.final.x, res.final.p)) });
  }
  return rec;
}
}

RayRecord FrameTracer::tracePixel(int i, int j, std::vector<PathPoint>* path) const
{
  ++this->RaysIntegrated;
  auto prop = makePropagator(*this->St, this->Desc.integrator);
  return traceWith(*this, *prop, this->Tracing, i, j, path);
}

RayRecord FrameTracer::traceAt(double x, double y) const
{
  ++this->RaysIntegrated;
  auto prop = makePropagator(*this->St, this->Desc.integrator);
  RayRecord r = traceWith(*this, *prop, this->Tracing, x, y, nullptr);
  r.dudi = r.dudj = r.dvdi = r.dvdj = std::numeric_limits<double>::quiet_NaN();
  return r;
}

RayRecord FrameTracer::traceThrough(Propagator& prop, double x, double y) const
{
  ++this->RaysIntegrated;
  return traceWith(*this, prop, this->Tracing, x, y, nullptr);
}

Color FrameTracer::pointColor(const JacobianSample& s) const
{
  const Scene& scene = *this->Desc.scene;
  return s.objectId >= 0 ? scene.shade(s.objectId, s.u, s.v) : scene.endColor(s.termination);
}

std::vector<std::pair<int, int>> edgeNeighbours(const std::vector<std::pair<int, int>>& pixels,
                                                int width, int height)
{
  std::vector<std::pair<int, int>> sorted = pixels;
  std::sort(sorted.begin(), sorted.end());
  std::vector<std::pair<int, int>> halo;
  for (const auto& [i, j] : pixels)
    for (const auto& [di, dj] :
         { std::pair(-1, 0), std::pair(1, 0), std::pair(0, -1), std::pair(0, 1) })
    {
      const std::pair<int, int> n(i + di, j + dj);
      if (n.first >= 0 && n.first < width && n.second >= 0 && n.second < height &&
          !std::binary_search(sorted.begin(), sorted.end(), n))
        halo.push_back(n);
    }
  std::sort(halo.begin(), halo.end());
  halo.erase(std::unique(halo.begin(), halo.end()), halo.end());
  return halo;
}

std::vector<JacobianSample> edgeNeighbourSamples(const std::vector<RayRecord>& frame, int width,
                                                 int height,
                                                 const std::vector<std::pair<int, int>>& pixels)
{
  std::vector<JacobianSample> border;
  for (const auto& [i, j] : edgeNeighbours(pixels, width, height))
    border.push_back(
      jacobianSample(frame.at(static_cast<std::size_t>(j) * static_cast<std::size_t>(width) +
                              static_cast<std::size_t>(i))));
  return border;
}

namespace
{
/// The pixels of the border samples, sorted.
std::vector<std::pair<int, int>> borderPixels(const std::vector<JacobianSample>& border)
{
  std::vector<std::pair<int, int>> given;
  given.reserve(border.size());
  for (const JacobianSample& s : border)
    given.emplace_back(s.i, s.j);
  std::sort(given.begin(), given.end());
  return given;
}

/// The edge neighbours of `pixels` not among `given` (sorted).
std::vector<std::pair<int, int>> neighboursNotGiven(const std::vector<std::pair<int, int>>& pixels,
                                                    int width, int height,
                                                    const std::vector<std::pair<int, int>>& given)
{
  std::vector<std::pair<int, int>> traced;
  for (const auto& n : edgeNeighbours(pixels, width, height))
    if (!std::binary_search(given.begin(), given.end(), n))
      traced.push_back(n);
  return traced;
}
}

std::vector<std::pair<int, int>> neighboursToTrace(const std::vector<std::pair<int, int>>& pixels,
                                                   int width, int height,
                                                   const std::vector<JacobianSample>& border)
{
  return neighboursNotGiven(pixels, width, height, borderPixels(border));
}

std::vector<RayRecord> FrameTracer::tracePixels(const std::vector<std::pair<int, int>>& pixels,
                                                CentreRays& kept,
                                                const std::function<bool(double)>& progress) const
{
  return this->tracePixelsBeside(pixels, {}, &kept, progress);
}

std::vector<RayRecord> FrameTracer::tracePixels(const std::vector<std::pair<int, int>>& pixels,
                                                const std::function<bool(double)>& progress) const
{
  return this->tracePixelsBeside(pixels, {}, nullptr, progress);
}

std::vector<RayRecord> FrameTracer::tracePixelsBeside(
  const std::vector<std::pair<int, int>>& pixels, const std::vector<JacobianSample>& border,
  CentreRays* kept, const std::function<bool(double)>& progress) const
{
  const int width = this->Desc.camera.width, height = this->Desc.camera.height;
  std::vector<std::pair<int, int>> asked = pixels;
  std::sort(asked.begin(), asked.end());
  const std::vector<std::pair<int, int>> given = borderPixels(border);
  for (const auto& [i, j] : given)
  {
    auto where = [&] { return "(" + std::to_string(i) + ", " + std::to_string(j) + ")"; };
    if (i < 0 || i >= width || j < 0 || j >= height)
      throw InvalidParameter("tracing beside given neighbours: the border sample of pixel " +
                             where() + " lies outside the " + std::to_string(width) + " x " +
                             std::to_string(height) + " frame");
    if (std::binary_search(asked.begin(), asked.end(), std::pair(i, j)))
      throw InvalidParameter("tracing beside given neighbours: pixel " + where() +
                             " is both asked for and given as a border sample");
  }
  if (std::adjacent_find(given.begin(), given.end()) != given.end())
    throw InvalidParameter("tracing beside given neighbours: a border sample is given twice");
  // The pixels' edge neighbours not given are traced too, as the halo rows of a band are: a
  // pixel's Jacobian and its anti-aliasing read its neighbours, so that with them (or with their
  // own rays given) a subset's records are the whole frame's records of those pixels, bit for bit.
  std::vector<std::pair<int, int>> all = pixels;
  const std::vector<std::pair<int, int>> halo = neighboursNotGiven(pixels, width, height, given);
  all.insert(all.end(), halo.begin(), halo.end());
  return this->traceKeeping(all, pixels.size(), progress, kept, border);
}

std::vector<RayRecord> FrameTracer::traceKeeping(const std::vector<std::pair<int, int>>& pixels,
                                                 std::size_t keep,
                                                 const std::function<bool(double)>& progress,
                                                 CentreRays* kept,
                                                 const std::vector<JacobianSample>& border) const
{
  // The centre rays take the first share of the progress; anti-aliasing reports the rest.
  const bool extra =
    this->Desc.rendering.mode == AntialiasMode::Adaptive || this->Desc.rendering.supersample > 1;
  const double share = extra ? 0.5 : 1.0;
  std::function<bool(double)> centreProgress, restProgress;
  if (progress)
  {
    centreProgress = [&](double f) { return progress(share * f); };
    restProgress = [&](double f) { return progress(share + (1.0 - share) * f); };
  }
  std::vector<RayRecord> out = this->traceCentresKept(pixels, centreProgress, kept, border);
  std::vector<JacobianSample> halo = border;
  for (std::size_t k = keep; k < out.size(); ++k)
    halo.push_back(jacobianSample(out[k]));
  out.resize(std::min(keep, out.size()));
  if (!progress || progress(share))
    this->antialias(out, halo, restProgress);
  return out;
}

std::vector<RayRecord> FrameTracer::traceCentres(const std::vector<std::pair<int, int>>& pixels,
                                                 const std::function<bool(double)>& progress) const
{
  return this->traceCentresKept(pixels, progress, nullptr);
}

std::vector<RayRecord> FrameTracer::traceCentresKept(
  const std::vector<std::pair<int, int>>& pixels, const std::function<bool(double)>& progress,
  CentreRays* kept, const std::vector<JacobianSample>& neighbours) const
{
  if (effectiveGridLattice(this->Desc.rendering) > 1)
  {
    std::vector<RayRecord> grid = this->traceGrid(pixels, progress);
    computeJacobians(grid, neighbours);
    return grid;
  }
  const long n = static_cast<long>(pixels.size());
  std::vector<RayRecord> out(pixels.size());
  const std::int64_t width = this->Desc.camera.width;
  auto keyOf = [width](const std::pair<int, int>& ij)
  { return static_cast<std::int64_t>(ij.second) * width + ij.first; };
  // Which centre rays `kept` held (left empty without it: a whole frame's rows pay nothing).
  std::vector<unsigned char> known(kept ? pixels.size() : 0, 0);
  if (kept)
    for (std::size_t k = 0; k < pixels.size(); ++k)
    {
      const auto found = kept->Records.find(keyOf(pixels[k]));
      if (found != kept->Records.end())
      {
        out[k] = found->second;
        known[k] = 1;
      }
    }
  std::atomic<long> done{ 0 };
  std::atomic<bool> stop{ false };
  const long reportEvery = std::max(1L, n / 200);
#pragma omp parallel if (n >= kParallelRays)
  {
    // One propagator per thread: it carries the state of the ray being traced.
    std::unique_ptr<Propagator> prop = makePropagator(*this->St, this->Desc.integrator);
    long lastReported = 0;
#pragma omp for schedule(dynamic, 8)
    for (long k = 0; k < n; ++k)
    {
      if (stop.load(std::memory_order_relaxed))
        continue;
      if (!kept || !known[static_cast<std::size_t>(k)])
        out[k] = this->traceThrough(*prop, pixels[k].first, pixels[k].second);
      const long d = ++done;
      // Only the master thread reports: VTK's progress events are not thread-safe.
      if (progress && omp_get_thread_num() == 0 && d - lastReported >= reportEvery)
      {
        lastReported = d;
        if (!progress(static_cast<double>(d) / n))
          stop = true;
      }
    }
  }
  // The whole set is done: say so from the calling thread, whichever threads traced the last rays
  // (the master's own reports above depend on how the rays were shared out).
  if (progress && !stop && n > 0)
    progress(1.0);
  if (kept)
    for (std::size_t k = 0; k < pixels.size(); ++k)
      if (!known[k] && out[k].termination != Termination::Running) // traced, not stopped early
        kept->Records.emplace(keyOf(pixels[k]), out[k]);
  computeJacobians(out, neighbours);
  return out;
}

std::vector<RayRecord> FrameTracer::traceRows(int rowBegin, int rowEnd,
                                              const std::function<bool(double)>& progress) const
{
  const int w = this->Desc.camera.width, h = this->Desc.camera.height;
  if (rowEnd <= rowBegin)
    return {};
  // The rows just outside the band are traced after it, only for its Jacobians and judgements.
  const int first = std::max(0, rowBegin - 1), last = std::min(h, rowEnd + 1);
  std::vector<std::pair<int, int>> pixels;
  pixels.reserve(static_cast<size_t>(std::max(0, last - first)) * w);
  for (int j = rowBegin; j < rowEnd; ++j)
    for (int i = 0; i < w; ++i)
      pixels.emplace_back(i, j);
  const std::size_t keep = pixels.size();
  for (int j : { first, last - 1 })
    if (j < rowBegin || j >= rowEnd)
      for (int i = 0; i < w; ++i)
        pixels.emplace_back(i, j);
  return this->traceKeeping(pixels, keep, progress);
}

void FrameTracer::computeJacobians(std::vector<RayRecord>& records,
                                   const std::vector<JacobianSample>& neighbours)
{
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const PixelLookup lookup(records, neighbours);
  auto at = [&](int i, int j) { return lookup.at(i, j); };
  auto same = [](const RayRecord& a, const JacobianSample* b)
  {
    return b && b->termination != Termination::Running && b->objectId == a.objectId &&
           b->imageOrder == a.imageOrder;
  };
  // Each record reads only the lookup and writes only itself: the records are shared among the
  // threads in any way, with the same result.
  const long n = static_cast<long>(records.size());
#pragma omp parallel for schedule(static) if (n > kParallelRecords)
  for (long k = 0; k < n; ++k)
  {
    RayRecord& r = records[static_cast<std::size_t>(k)];
    // An interpolated record keeps the Jacobian of its interpolant (AdaptiveGrid.h).
    if (!r.traced)
      continue;
    if (r.objectId < 0)
    {
      r.dudi = r.dudj = r.dvdi = r.dvdj = nan;
      continue;
    }
    auto derivative =
      [&](const JacobianSample* minus, const JacobianSample* plus, double& dU, double& dV)
    {
      const bool m = same(r, minus), p = same(r, plus);
      if (m && p)
      {
        dU = 0.5 * shortUDifference(plus->u, minus->u);
        dV = 0.5 * (plus->v - minus->v);
      }
      else if (p)
      {
        dU = shortUDifference(plus->u, r.u);
        dV = plus->v - r.v;
      }
      else if (m)
      {
        dU = shortUDifference(r.u, minus->u);
        dV = r.v - minus->v;
      }
      else
      {
        dU = dV = nan;
      }
    };
    derivative(at(r.i - 1, r.j), at(r.i + 1, r.j), r.dudi, r.dvdi);
    derivative(at(r.i, r.j - 1), at(r.i, r.j + 1), r.dudj, r.dvdj);
  }
}
}
