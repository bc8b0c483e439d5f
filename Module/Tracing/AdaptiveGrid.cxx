// The adaptive ray grid (AdaptiveGrid.h) and FrameTracer::traceGrid, which traces a frame's centre
// rays on it.
#include "AdaptiveGrid.h"

#include "FrameTracer.h"

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <thread>
#include <unordered_map>

namespace asrt
{
namespace
{
/// The block's corner column (row) a sub-quad starts at for a pixel coordinate: the first where
/// the pixel lies before the midpoint, else the second (a degenerate first half has no pixels).
int half(int x, int xm)
{
  return x < xm ? 0 : 1;
}

double fraction(int x, int xa, int xb)
{
  return xb > xa ? static_cast<double>(x - xa) / (xb - xa) : 0.0;
}

/// Lagrange's weights on the nodes 0, m, 1 (0 < m < 1) at s, and their derivatives in s.
struct QuadraticWeights
{
  double w[3], dw[3];
  QuadraticWeights(double s, double m)
  {
    w[0] = (s - m) * (s - 1.0) / m;
    w[1] = s * (s - 1.0) / (m * (m - 1.0));
    w[2] = s * (s - m) / (1.0 - m);
    dw[0] = (2.0 * s - m - 1.0) / m;
    dw[1] = (2.0 * s - 1.0) / (m * (m - 1.0));
    dw[2] = (2.0 * s - m) / (1.0 - m);
  }
};

/// The biquadratic through a block's 9 points (blockPoints' order) at pixel (i, j), with its
/// derivatives along i and j.
struct Biquadratic
{
  QuadraticWeights x, y;
  double wx, wy; // the block's sides in pixels
  Biquadratic(const GridBlock& b, int i, int j)
    : x(fraction(i, b.x0, b.x1), fraction(b.xm(), b.x0, b.x1))
    , y(fraction(j, b.y0, b.y1), fraction(b.ym(), b.y0, b.y1))
    , wx(b.x1 - b.x0)
    , wy(b.y1 - b.y0)
  {
  }
  template<typename T, typename Get>
  T value(const Get& f) const
  {
    T sum = x.w[0] * y.w[0] * f(0);
    for (int k = 1; k < 9; ++k)
      sum += x.w[k % 3] * y.w[k / 3] * f(k);
    return sum;
  }
  template<typename Get>
  double di(const Get& f) const
  {
    return weighted(x.dw, y.w, f) / wx;
  }
  template<typename Get>
  double dj(const Get& f) const
  {
    return weighted(x.w, y.dw, f) / wy;
  }

private:
  /// Σ a[k mod 3] b[k div 3] f(k) over the 9 points.
  template<typename Get>
  static double weighted(const double (&a)[3], const double (&b)[3], const Get& f)
  {
    double sum = 0.0;
    for (int k = 0; k < 9; ++k)
      sum += a[k % 3] * b[k / 3] * f(k);
    return sum;
  }
};

/// The bilinear interpolant on one sub-quad: f(s, t) = f00 + s Δ10 + t Δ01 + s t (Δ11 − Δ10 − Δ01)
/// with Δ the corners' differences from f00.
struct Bilinear
{
  double s, t;
  template<typename T>
  T operator()(const T& f00, const T& f10, const T& f01, const T& f11) const
  {
    return f00 + s * (f10 - f00) + t * (f01 - f00) + s * t * (f11 - f10 - f01 + f00);
  }
};

/// The record of pixel (i, j) of a block whose rays end as `c00` does, before its interpolated
/// fields: the block's ending and eye, no ray traced, and no Jacobian (NaN) until a surface's is
/// filled in.
RayRecord untracedRecord(const RayRecord& c00, int i, int j)
{
  RayRecord r;
  r.i = i;
  r.j = j;
  r.origin = c00.origin;
  r.termination = c00.termination;
  r.objectId = c00.objectId;
  r.imageOrder = c00.imageOrder;
  r.steps = 0;
  r.traced = false;
  r.raysPerPixel = 0;
  r.dudi = r.dudj = r.dvdi = r.dvdj = std::numeric_limits<double>::quiet_NaN();
  return r;
}

/// u unwrapped past the seam, back in [0, 1).
double wrappedU(double u)
{
  return u < 0.0 || u >= 1.0 ? u - std::floor(u) : u;
}
}

GridBlock latticeBlock(int i, int j, int lattice, int width, int height)
{
  // Corners at multiples of the lattice; the last block of a row (column) ends at the frame's
  // edge, and a pixel on that edge belongs to it.
  auto range = [lattice](int x, int size, int& a, int& b)
  {
    const int last = std::max(0, size - 1);
    a = std::min(x, last) / lattice * lattice;
    if (a == last && a > 0)
      a -= (a - 1) % lattice + 1; // the frame's last line, on the lattice: the block before it
    b = std::min(a + lattice, last);
  };
  GridBlock g;
  range(i, width, g.x0, g.x1);
  range(j, height, g.y0, g.y1);
  return g;
}

bool ownsPixel(const GridBlock& b, int i, int j, int width, int height)
{
  const bool inI = (i >= b.x0 && i < b.x1) || (i == b.x1 && b.x1 == width - 1);
  const bool inJ = (j >= b.y0 && j < b.y1) || (j == b.y1 && b.y1 == height - 1);
  return inI && inJ;
}

std::array<std::pair<int, int>, 9> blockPoints(const GridBlock& b)
{
  const int xs[3] = { b.x0, b.xm(), b.x1 }, ys[3] = { b.y0, b.ym(), b.y1 };
  std::array<std::pair<int, int>, 9> p;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      p[static_cast<std::size_t>(3 * r + c)] = { xs[c], ys[r] };
  return p;
}

bool blockEndsAlike(const std::array<const RayRecord*, 9>& p)
{
  for (const RayRecord* r : p)
    if (!endsAlike(*r, *p[0]))
      return false;
  // Rays the integrator lost are never interpolated: a block of them refines to its pixels.
  const Termination t = p[0]->termination;
  return t == Termination::HitObject || t == Termination::Escaped || t == Termination::Captured;
}

bool blockIsSmooth(const GridBlock& b, const std::array<const RayRecord*, 9>& p, double tolerance)
{
  if (!blockEndsAlike(p))
    return false;
  if (p[0]->objectId < 0)
    return true;
  // The bilinear map of the 4 corners at the 5 other points.
  const RayRecord &c00 = *p[0], &c10 = *p[2], &c01 = *p[6], &c11 = *p[8];
  const double d10 = shortUDifference(c10.u, c00.u), d01 = shortUDifference(c01.u, c00.u),
               d11 = shortUDifference(c11.u, c00.u);
  for (int k : { 1, 3, 4, 5, 7 })
  {
    const RayRecord& r = *p[static_cast<std::size_t>(k)];
    const Bilinear at{ fraction(r.i, b.x0, b.x1), fraction(r.j, b.y0, b.y1) };
    const double u = c00.u + at(0.0, d10, d01, d11);
    const double v = at(c00.v, c10.v, c01.v, c11.v);
    if (!(std::abs(shortUDifference(u, r.u)) <= tolerance && std::abs(v - r.v) <= tolerance))
      return false;
  }
  return true;
}

RayRecord interpolateRecord(const GridBlock& b, const std::array<const RayRecord*, 9>& p, int i,
                            int j)
{
  const int xs[3] = { b.x0, b.xm(), b.x1 }, ys[3] = { b.y0, b.ym(), b.y1 };
  const int a = half(i, xs[1]), c = half(j, ys[1]);
  const RayRecord& c00 = *p[static_cast<std::size_t>(3 * c + a)];
  const RayRecord& c10 = *p[static_cast<std::size_t>(3 * c + a + 1)];
  const RayRecord& c01 = *p[static_cast<std::size_t>(3 * c + a + 3)];
  const RayRecord& c11 = *p[static_cast<std::size_t>(3 * c + a + 4)];
  const int wx = xs[a + 1] - xs[a], wy = ys[c + 1] - ys[c];
  const Bilinear at{ fraction(i, xs[a], xs[a + 1]), fraction(j, ys[c], ys[c + 1]) };
  const double nan = std::numeric_limits<double>::quiet_NaN();

  RayRecord r = untracedRecord(c00, i, j);
  r.hitPoint = at(c00.hitPoint, c10.hitPoint, c01.hitPoint, c11.hitPoint);
  r.affineLength = at(c00.affineLength, c10.affineLength, c01.affineLength, c11.affineLength);
  r.winding = at(c00.winding, c10.winding, c01.winding, c11.winding);
  r.chordError = std::max({ c00.chordError, c10.chordError, c01.chordError, c11.chordError });
  r.maxAbsH = std::max({ c00.maxAbsH, c10.maxAbsH, c01.maxAbsH, c11.maxAbsH });
  if (r.objectId < 0)
    return r;
  const Vec3 n = at(c00.hitNormal, c10.hitNormal, c01.hitNormal, c11.hitNormal);
  r.hitNormal = n.norm() > 0 ? Vec3(n.normalized()) : c00.hitNormal;
  // u unwrapped from the first corner the short way; back in [0, 1) if that crossed the seam.
  const double d10 = shortUDifference(c10.u, c00.u), d01 = shortUDifference(c01.u, c00.u),
               d11 = shortUDifference(c11.u, c00.u);
  r.u = wrappedU(c00.u + at(0.0, d10, d01, d11));
  r.v = at(c00.v, c10.v, c01.v, c11.v);
  // The derivatives of the bilinear map at the pixel.
  const double cross = d11 - d10 - d01, crossV = c11.v - c10.v - c01.v + c00.v;
  r.dudi = wx > 0 ? (d10 + at.t * cross) / wx : nan;
  r.dvdi = wx > 0 ? ((c10.v - c00.v) + at.t * crossV) / wx : nan;
  r.dudj = wy > 0 ? (d01 + at.s * cross) / wy : nan;
  r.dvdj = wy > 0 ? ((c01.v - c00.v) + at.s * crossV) / wy : nan;
  return r;
}

bool admitsQuadratic(const GridBlock& b)
{
  return b.x1 - b.x0 >= 8 && b.y1 - b.y0 >= 8;
}

std::array<std::pair<int, int>, 4> quarterCentres(const GridBlock& b)
{
  const int xm = b.xm(), ym = b.ym();
  const GridBlock q[4] = {
    { b.x0, b.y0, xm, ym }, { xm, b.y0, b.x1, ym }, { b.x0, ym, xm, b.y1 }, { xm, ym, b.x1, b.y1 }
  };
  std::array<std::pair<int, int>, 4> c;
  for (std::size_t k = 0; k < 4; ++k)
    c[k] = { q[k].xm(), q[k].ym() };
  return c;
}

bool quadraticFits(const GridBlock& b, const std::array<const RayRecord*, 9>& p,
                   const std::array<const RayRecord*, 4>& q, double tolerance)
{
  const RayRecord& c00 = *p[0];
  auto du = [&](int k) { return shortUDifference(p[static_cast<std::size_t>(k)]->u, c00.u); };
  auto v = [&](int k) { return p[static_cast<std::size_t>(k)]->v; };
  for (const RayRecord* r : q)
  {
    if (!endsAlike(*r, c00))
      return false;
    const Biquadratic at(b, r->i, r->j);
    const double u = c00.u + at.value<double>(du);
    if (!(std::abs(shortUDifference(u, r->u)) <= tolerance &&
          std::abs(at.value<double>(v) - r->v) <= tolerance))
      return false;
  }
  return true;
}

RayRecord interpolateRecordQuadratic(const GridBlock& b, const std::array<const RayRecord*, 9>& p,
                                     int i, int j)
{
  const RayRecord& c00 = *p[0];
  const Biquadratic at(b, i, j);
  auto rec = [&](int k) -> const RayRecord& { return *p[static_cast<std::size_t>(k)]; };
  RayRecord r = untracedRecord(c00, i, j);
  r.hitPoint = at.value<Vec3>([&](int k) { return rec(k).hitPoint; });
  r.affineLength = at.value<double>([&](int k) { return rec(k).affineLength; });
  r.winding = at.value<double>([&](int k) { return rec(k).winding; });
  for (int k = 0; k < 9; ++k)
  {
    r.chordError = std::max(r.chordError, rec(k).chordError);
    r.maxAbsH = std::max(r.maxAbsH, rec(k).maxAbsH);
  }
  if (r.objectId < 0)
    return r;
  const Vec3 n = at.value<Vec3>([&](int k) { return rec(k).hitNormal; });
  r.hitNormal = n.norm() > 0 ? Vec3(n.normalized()) : c00.hitNormal;
  auto du = [&](int k) { return shortUDifference(rec(k).u, c00.u); };
  auto v = [&](int k) { return rec(k).v; };
  r.u = wrappedU(c00.u + at.value<double>(du));
  r.v = at.value<double>(v);
  r.dudi = at.di(du);
  r.dvdi = at.di(v);
  r.dudj = at.dj(du);
  r.dvdj = at.dj(v);
  return r;
}

std::vector<GridBlock> latticeBlocksOf(const std::vector<std::pair<int, int>>& pixels, int lattice,
                                       int width, int height)
{
  std::vector<GridBlock> blocks;
  for (const auto& [i, j] : pixels)
  {
    // Pixels come mostly in rows: a run of them in one block adds it once.
    const GridBlock g = latticeBlock(i, j, lattice, width, height);
    if (blocks.empty() || !(blocks.back() == g))
      blocks.push_back(g);
  }
  auto order = [](const GridBlock& a, const GridBlock& b)
  { return std::tie(a.y0, a.x0, a.y1, a.x1) < std::tie(b.y0, b.x0, b.y1, b.x1); };
  std::sort(blocks.begin(), blocks.end(), order);
  blocks.erase(std::unique(blocks.begin(), blocks.end()), blocks.end());
  return blocks;
}

namespace
{
/// The rays on the borders of lattice blocks, which the blocks either side of a border (four at a
/// lattice point) all need: each is traced once, by the first thread to ask, and copied by the
/// others. A ray is a function of its pixel alone, so which block traces it changes nothing in
/// the frame; tracing them in every block instead cost 1.3 to 2.25 times the unique rays.
class SharedBorderRays
{
public:
  template<typename Trace>
  const RayRecord& get(long key, const Trace& trace)
  {
    Entry* e;
    {
      const std::lock_guard<std::mutex> lock(this->Mutex);
      std::unique_ptr<Entry>& slot = this->Entries[key];
      if (!slot)
        slot = std::make_unique<Entry>();
      e = slot.get();
    }
    int expected = 0;
    if (e->state.compare_exchange_strong(expected, 1, std::memory_order_acq_rel))
    {
      e->record = trace();
      e->state.store(2, std::memory_order_release);
    }
    else
    {
      // Another thread is tracing it: one ray's wait at most, and only where two threads work on
      // neighbouring blocks at once.
      while (e->state.load(std::memory_order_acquire) != 2)
        std::this_thread::yield();
    }
    return e->record;
  }

private:
  struct Entry
  {
    std::atomic<int> state{ 0 }; // 0 untraced, 1 being traced, 2 ready
    RayRecord record;
  };
  std::mutex Mutex;
  std::unordered_map<long, std::unique_ptr<Entry>> Entries;
};
}

/// The rays and interpolations of one lattice block, over its closed pixel range.
struct FrameTracer::GridWork
{
  void reset(const GridBlock& b)
  {
    this->Block = b;
    this->W = b.x1 - b.x0 + 1;
    const std::size_t n = static_cast<std::size_t>(this->W) * (b.y1 - b.y0 + 1);
    this->Traced.assign(n, 0);
    this->Filled.assign(n, 0);
    this->Rays.resize(n);
    this->Fills.resize(n);
  }
  std::size_t slot(int i, int j) const
  {
    return static_cast<std::size_t>(j - this->Block.y0) * this->W + (i - this->Block.x0);
  }
  /// The pixel's record: its ray if this block traced it, else its interpolation.
  const RayRecord& record(int i, int j) const
  {
    const std::size_t k = this->slot(i, j);
    return this->Traced[k] ? this->Rays[k] : this->Fills[k];
  }

  /// Whether the pixel's ray is one other lattice blocks may need too: on the lattice block's
  /// border, shared with its neighbours, or its centre, which its neighbours may look at
  /// (capturedBesideOtherEndings).
  bool shared(int i, int j) const
  {
    return i == this->Block.x0 || i == this->Block.x1 || j == this->Block.y0 ||
           j == this->Block.y1 || (i == this->Block.xm() && j == this->Block.ym());
  }

  GridBlock Block;
  int W = 0;
  std::vector<unsigned char> Traced, Filled;
  std::vector<RayRecord> Rays, Fills;
  SharedBorderRays* Shared = nullptr;
  int FrameWidth = 0;
};

const RayRecord& FrameTracer::gridRay(Propagator& prop, int i, int j, GridWork& work) const
{
  const std::size_t s = work.slot(i, j);
  if (!work.Traced[s])
  {
    if (work.Shared && work.shared(i, j))
      work.Rays[s] = this->sharedGridRay(prop, i, j, work);
    else
      work.Rays[s] = this->traceThrough(prop, i, j);
    work.Traced[s] = 1;
  }
  return work.Rays[s];
}

const RayRecord& FrameTracer::sharedGridRay(Propagator& prop, int i, int j, GridWork& work) const
{
  return work.Shared->get(static_cast<long>(j) * work.FrameWidth + i,
                          [&] { return this->traceThrough(prop, i, j); });
}

bool FrameTracer::capturedBesideOtherEndings(Propagator& prop, const GridBlock& b,
                                             GridWork& work) const
{
  const int W = this->Desc.camera.width, H = this->Desc.camera.height;
  const int lattice = this->Desc.rendering.gridLattice;
  auto fallsIn = [&](int i, int j)
  { return this->sharedGridRay(prop, i, j, work).termination == Termination::Captured; };
  // Each edge neighbour's line of points nearest to the block: its middle row (column).
  auto row = [&](const GridBlock& n)
  { return fallsIn(n.x0, n.ym()) && fallsIn(n.xm(), n.ym()) && fallsIn(n.x1, n.ym()); };
  auto column = [&](const GridBlock& n)
  { return fallsIn(n.xm(), n.y0) && fallsIn(n.xm(), n.ym()) && fallsIn(n.xm(), n.y1); };
  return (b.y0 > 0 && !row(latticeBlock(b.x0, b.y0 - 1, lattice, W, H))) ||
         (b.y1 < H - 1 && !row(latticeBlock(b.x0, b.y1, lattice, W, H))) ||
         (b.x0 > 0 && !column(latticeBlock(b.x0 - 1, b.y0, lattice, W, H))) ||
         (b.x1 < W - 1 && !column(latticeBlock(b.x1, b.y0, lattice, W, H)));
}

void FrameTracer::refineBlock(Propagator& prop, const GridBlock& b, GridWork& work) const
{
  const int W = this->Desc.camera.width, H = this->Desc.camera.height;
  const auto points = blockPoints(b);
  std::array<const RayRecord*, 9> p;
  for (std::size_t k = 0; k < 9; ++k)
    p[k] = &this->gridRay(prop, points[k].first, points[k].second, work);
  // At most 2 pixels a side, every pixel is one of the 9 points.
  if (b.x1 - b.x0 <= 2 && b.y1 - b.y0 <= 2)
    return;
  // Fills the block's pixels that no ray was traced for from an interpolation of its points.
  auto fill = [&](const auto& interpolate)
  {
    for (int j = b.y0; j <= b.y1; ++j)
      for (int i = b.x0; i <= b.x1; ++i)
      {
        const std::size_t s = work.slot(i, j);
        if (work.Traced[s] || !ownsPixel(b, i, j, W, H))
          continue;
        RayRecord r = interpolate(i, j);
        r.direction = this->Cam->localDirection(i, j);
        r.momentum = this->Cam->pixelRay(i, j).p;
        r.color = this->pointColor(jacobianSample(r));
        work.Fills[s] = r;
        work.Filled[s] = 1;
      }
  };
  const double tolerance = this->Desc.rendering.gridTolerance;
  // The lens compresses images most inside the shadow: an object's image running into a block
  // whose points all fell into the hole can thin there below their spacing (the tip of the image
  // of a rod that passes near the horizon). Such a lattice block is split once, its quarters
  // refining as any block, when a neighbouring lattice block's nearest points do not all fall in.
  const bool splitOnce = b == work.Block && p[0]->termination == Termination::Captured &&
                         blockEndsAlike(p) && work.Shared &&
                         this->capturedBesideOtherEndings(prop, b, work);
  if (!splitOnce && blockIsSmooth(b, p, tolerance))
  {
    fill([&](int i, int j) { return interpolateRecord(b, p, i, j); });
    return;
  }
  // Ending alike on a surface whose (u, v) bends: the biquadratic through the 9 points, if it
  // predicts the quarters' centres (which the quarters would trace anyway).
  if (admitsQuadratic(b) && p[0]->objectId >= 0 && blockEndsAlike(p))
  {
    std::array<const RayRecord*, 4> q;
    const auto centres = quarterCentres(b);
    for (std::size_t k = 0; k < 4; ++k)
      q[k] = &this->gridRay(prop, centres[k].first, centres[k].second, work);
    if (quadraticFits(b, p, q, tolerance))
    {
      fill([&](int i, int j) { return interpolateRecordQuadratic(b, p, i, j); });
      return;
    }
  }
  // Split at the midpoints; a side of at most 2 pixels stays whole.
  const int xm = b.xm(), ym = b.ym();
  std::vector<std::pair<int, int>> xr, yr;
  if (b.x1 - b.x0 > 2)
    xr = { { b.x0, xm }, { xm, b.x1 } };
  else
    xr = { { b.x0, b.x1 } };
  if (b.y1 - b.y0 > 2)
    yr = { { b.y0, ym }, { ym, b.y1 } };
  else
    yr = { { b.y0, b.y1 } };
  for (const auto& [y0, y1] : yr)
    for (const auto& [x0, x1] : xr)
      this->refineBlock(prop, GridBlock{ x0, y0, x1, y1 }, work);
}

std::vector<RayRecord> FrameTracer::traceGrid(const std::vector<std::pair<int, int>>& pixels,
                                              const std::function<bool(double)>& progress) const
{
  const int W = this->Desc.camera.width, H = this->Desc.camera.height;
  const int lattice = this->Desc.rendering.gridLattice;
  const std::vector<GridBlock> blocks = latticeBlocksOf(pixels, lattice, W, H);
  // Which of the requested pixels each block hands out.
  auto order = [](const GridBlock& a, const GridBlock& b)
  { return std::tie(a.y0, a.x0, a.y1, a.x1) < std::tie(b.y0, b.x0, b.y1, b.x1); };
  std::vector<std::vector<std::size_t>> wanted(blocks.size());
  GridBlock last{ -1, -1, -1, -1 };
  std::size_t lastIndex = 0;
  for (std::size_t k = 0; k < pixels.size(); ++k)
  {
    const GridBlock g = latticeBlock(pixels[k].first, pixels[k].second, lattice, W, H);
    if (!(g == last))
    {
      last = g;
      lastIndex = static_cast<std::size_t>(
        std::lower_bound(blocks.begin(), blocks.end(), g, order) - blocks.begin());
    }
    wanted[lastIndex].push_back(k);
  }

  std::vector<RayRecord> out(pixels.size());
  const long n = static_cast<long>(blocks.size());
  std::atomic<long> done{ 0 };
  std::atomic<bool> stop{ false };
  const long reportEvery = std::max(1L, n / 200);
  SharedBorderRays shared;
#pragma omp parallel if (n * kRaysPerItem >= kParallelRays)
  {
    std::unique_ptr<Propagator> prop = makePropagator(*this->St, this->Desc.integrator);
    GridWork work;
    work.Shared = &shared;
    work.FrameWidth = W;
    long lastReported = 0;
#pragma omp for schedule(dynamic, 1)
    for (long q = 0; q < n; ++q)
    {
      if (stop.load(std::memory_order_relaxed))
        continue;
      const GridBlock& b = blocks[static_cast<std::size_t>(q)];
      work.reset(b);
      this->refineBlock(*prop, b, work);
      for (std::size_t k : wanted[static_cast<std::size_t>(q)])
        out[k] = work.record(pixels[k].first, pixels[k].second);
      const long d = ++done;
      if (progress && omp_get_thread_num() == 0 && d - lastReported >= reportEvery)
      {
        lastReported = d;
        if (!progress(static_cast<double>(d) / n))
          stop = true;
      }
    }
  }
  if (progress && !stop && n > 0)
    progress(1.0);
  return out;
}
}
