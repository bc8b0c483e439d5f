#include "FrameTracer.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

namespace asrt
{
namespace
{
double angleBetween(const Vec3& a, const Vec3& b)
{
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

/// Diagnostic colour of rays the integrator lost: never a colour of a real scene.
const Color failureColor(1.0, 0.0, 1.0);
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
    switch (res.termination)
    {
      case Termination::Captured:
        rec.color = scene.horizonColor;
        break;
      case Termination::Escaped:
        rec.color = scene.background;
        break;
      default:
        rec.color = failureColor;
    }
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
  auto prop = makePropagator(*this->St, this->Desc.integrator);
  return traceWith(*this, *prop, this->Tracing, i, j, path);
}

RayRecord FrameTracer::traceAt(double x, double y) const
{
  auto prop = makePropagator(*this->St, this->Desc.integrator);
  RayRecord r = traceWith(*this, *prop, this->Tracing, x, y, nullptr);
  r.dudi = r.dudj = r.dvdi = r.dvdj = std::numeric_limits<double>::quiet_NaN();
  return r;
}

std::vector<RayRecord> FrameTracer::tracePixels(const std::vector<std::pair<int, int>>& pixels,
                                                const std::function<bool(double)>& progress) const
{
  const long n = static_cast<long>(pixels.size());
  std::vector<RayRecord> out(pixels.size());
  std::atomic<long> done{ 0 };
  std::atomic<bool> stop{ false };
  const long reportEvery = std::max(1L, n / 200);
#pragma omp parallel
  {
    // One propagator per thread: it carries the state of the ray being traced.
    std::unique_ptr<Propagator> prop = makePropagator(*this->St, this->Desc.integrator);
    long lastReported = 0;
#pragma omp for schedule(dynamic, 8)
    for (long k = 0; k < n; ++k)
    {
      if (stop.load(std::memory_order_relaxed))
        continue;
      out[k] = traceWith(*this, *prop, this->Tracing, pixels[k].first, pixels[k].second, nullptr);
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
  computeJacobians(out);
  return out;
}

std::vector<RayRecord> FrameTracer::traceRows(int rowBegin, int rowEnd,
                                              const std::function<bool(double)>& progress) const
{
  const int w = this->Desc.camera.width, h = this->Desc.camera.height;
  if (rowEnd <= rowBegin)
    return {};
  const int first = std::max(0, rowBegin - 1), last = std::min(h, rowEnd + 1);
  std::vector<std::pair<int, int>> pixels;
  pixels.reserve(static_cast<size_t>(std::max(0, last - first)) * w);
  for (int j = first; j < last; ++j)
    for (int i = 0; i < w; ++i)
      pixels.emplace_back(i, j);
  std::vector<RayRecord> records = this->tracePixels(pixels, progress);
  // Drop the halo rows, which were traced only for their neighbours' Jacobians.
  const size_t before = static_cast<size_t>(rowBegin - first) * w;
  const size_t after = static_cast<size_t>(last - std::max(rowBegin, rowEnd)) * w;
  records.erase(records.end() - static_cast<std::ptrdiff_t>(std::min(after, records.size())),
                records.end());
  records.erase(records.begin(),
                records.begin() + static_cast<std::ptrdiff_t>(std::min(before, records.size())));
  return records;
}

void FrameTracer::computeJacobians(std::vector<RayRecord>& records,
                                   const std::vector<JacobianSample>& neighbours)
{
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<JacobianSample> samples;
  samples.reserve(records.size() + neighbours.size());
  for (const RayRecord& r : records)
    samples.push_back(jacobianSample(r));
  samples.insert(samples.end(), neighbours.begin(), neighbours.end());
  if (samples.empty())
    return;
  // Pixels by (i, j): a dense grid over their bounding box when they fill much of it (a frame,
  // bands or interleaved rows of one), a hash map when they are scattered (a pixel subset).
  int iMin = samples[0].i, iMax = iMin, jMin = samples[0].j, jMax = jMin;
  for (const JacobianSample& s : samples)
  {
    iMin = std::min(iMin, s.i);
    iMax = std::max(iMax, s.i);
    jMin = std::min(jMin, s.j);
    jMax = std::max(jMax, s.j);
  }
  const std::int64_t boxWidth = std::int64_t(iMax) - iMin + 1;
  const std::int64_t box = boxWidth * (std::int64_t(jMax) - jMin + 1);
  const bool dense = box <= 4 * static_cast<std::int64_t>(samples.size());
  std::vector<std::int64_t> grid(dense ? static_cast<std::size_t>(box) : 0, -1);
  std::unordered_map<std::int64_t, std::size_t> index;
  auto key = [](int i, int j)
  { return (static_cast<std::int64_t>(j) << 32) ^ static_cast<std::uint32_t>(i); };
  for (std::size_t k = 0; k < samples.size(); ++k)
  {
    if (dense)
    {
      std::int64_t& slot =
        grid[static_cast<std::size_t>((samples[k].j - jMin) * boxWidth + (samples[k].i - iMin))];
      if (slot < 0)
        slot = static_cast<std::int64_t>(k);
    }
    else
      index.emplace(key(samples[k].i, samples[k].j), k);
  }
  auto at = [&](int i, int j) -> const JacobianSample*
  {
    if (dense)
    {
      if (i < iMin || i > iMax || j < jMin || j > jMax)
        return nullptr;
      const std::int64_t k = grid[static_cast<std::size_t>((j - jMin) * boxWidth + (i - iMin))];
      return k < 0 ? nullptr : &samples[static_cast<std::size_t>(k)];
    }
    const auto it = index.find(key(i, j));
    return it == index.end() ? nullptr : &samples[it->second];
  };
  auto same = [](const RayRecord& a, const JacobianSample* b)
  {
    return b && b->termination != Termination::Running && b->objectId == a.objectId &&
           b->imageOrder == a.imageOrder;
  };
  // u is periodic on closed surfaces: a difference is taken as the short way round.
  auto du = [](double a, double b) { return (a - b) - std::round(a - b); };
  for (RayRecord& r : records)
  {
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
        dU = 0.5 * du(plus->u, minus->u);
        dV = 0.5 * (plus->v - minus->v);
      }
      else if (p)
      {
        dU = du(plus->u, r.u);
        dV = plus->v - r.v;
      }
      else if (m)
      {
        dU = du(r.u, minus->u);
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
