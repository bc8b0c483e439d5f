#include "Scene.h"

#include "ObjectHierarchy.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <mutex>
#include <sstream>

namespace asrt
{
namespace
{
constexpr double twoPi = 2.0 * M_PI;

[[noreturn]] void invalid(const std::string& msg)
{
  throw InvalidParameter(msg);
}

std::string show(const Vec3& v)
{
  std::ostringstream os;
  os << '(' << v.x() << ", " << v.y() << ", " << v.z() << ')';
  return os.str();
}

void requireFinite3(const Vec3& v, const std::string& what)
{
  if (!v.allFinite())
    invalid(what + " must be finite, got " + show(v));
}

void requirePositive(double v, const std::string& what)
{
  if (!(std::isfinite(v) && v > 0.0))
  {
    std::ostringstream os;
    os << what << " must be positive and finite, got " << v;
    invalid(os.str());
  }
}

Vec3 unitAxis(const Vec3& a, const std::string& what)
{
  requireFinite3(a, what);
  const double n = a.norm();
  // Squared components below ~1e-300 underflow the norm: such an axis has no usable direction.
  if (!(n > 1e-150) || !std::isfinite(n))
    invalid(what + " must be a nonzero vector, got " + show(a));
  return a / n;
}

/// Angle about an axis as a fraction of a turn, in [0, 1).
double turnFraction(double c1, double c2)
{
  double u = std::atan2(c2, c1) / twoPi;
  if (u < 0.0)
    u += 1.0;
  return u >= 1.0 ? 0.0 : u; // atan2 of (−0, −1) rounds to exactly one turn
}

/// Both real roots of A τ² + B τ + C = 0 (A > 0), ascending; the cancellation-free form of
/// Numerical Recipes §5.6. False if the discriminant is negative.
bool quadraticRoots(double A, double B, double C, double& t0, double& t1)
{
  const double disc = B * B - 4.0 * A * C;
  if (!(disc >= 0.0) || !(A > 0.0))
    return false;
  const double q = -0.5 * (B + std::copysign(std::sqrt(disc), B));
  if (q == 0.0)
  {
    t0 = t1 = 0.0; // B = C = 0: a double root at the origin
    return true;
  }
  t0 = q / A;
  t1 = C / q;
  if (t0 > t1)
    std::swap(t0, t1);
  return true;
}

bool inUnit(double t)
{
  return t >= 0.0 && t <= 1.0;
}
}

// ---------------------------------------------------------------------------------------------
void perpendicularBasis(const Vec3& n, Vec3& e1, Vec3& e2)
{
  int k = 0;
  for (int i = 1; i < 3; ++i)
  {
    if (std::abs(n[i]) < std::abs(n[k]))
      k = i;
  }
  const Vec3 e = Vec3::Unit(k);
  e1 = (e - e.dot(n) * n).normalized();
  e2 = n.cross(e1);
}

// ---------------------------------------------------------------------------------------------
SceneObject::SceneObject(int id, std::string name, std::shared_ptr<const Texture> texture)
  : Id(id)
  , Name(std::move(name))
  , Tex(std::move(texture))
{
  if (id < 0)
    invalid("object id must be non-negative (-1 means no object), got " + std::to_string(id));
  if (!this->Tex)
    invalid("object " + std::to_string(id) + " (\"" + this->Name + "\") has no texture");
}

double SceneObject::distanceFrom(const Vec3& x) const
{
  Vec3 c;
  double r;
  return this->boundingSphere(c, r) ? std::max(0.0, (x - c).norm() - r) : 0.0;
}

bool SceneObject::intersect(const Segment& seg, SurfaceHit& hit) const
{
  const Vec3 a = seg.x0.tail<3>(), b = seg.x1.tail<3>();
  double tc;
  if (!this->chordHit(a, b, tc))
    return false;
  const Vec3 chord = a + tc * (b - a);

  // Every implicit function here has |∇F| = 1 on its surface, so F and the Newton step measure
  // distance: both stop at a few hundred ulps of the coordinates' size.
  const double tolX =
    256.0 * std::numeric_limits<double>::epsilon() * (1.0 + std::max(a.norm(), b.norm()));
  Vec3 grad;
  auto f = [&](double t) { return this->implicit(seg.position(t).tail<3>(), grad); };

  // Newton on f(τ) = F(x(τ)) along the Hermite interpolant, f'(τ) = ∇F · dx/dτ, from the chord's τ:
  // the curve's crossing lies O(h²) away from it, well inside Newton's basin for any step that
  // resolves the ray.
  double t = tc;
  bool converged = false;
  for (int k = 0; k < 16 && !converged; ++k)
  {
    const double F = f(t);
    if (!std::isfinite(F))
      break;
    if (std::abs(F) <= tolX)
    {
      converged = true;
      break;
    }
    const Vec3 T = seg.tangent(t).tail<3>();
    const double dF = grad.dot(T);
    if (!(std::abs(dF) > 0.0) || !std::isfinite(dF))
      break; // grazing: no Newton step
    const double tn = t - F / dF;
    if (!(tn >= 0.0 && tn <= 1.0))
      break; // Newton left the step
    converged = std::abs(tn - t) * T.norm() <= tolX;
    t = tn;
  }

  if (!converged)
  {
    // Safeguard: bisection on the narrowest bracket about the chord's τ that changes sign. It is
    // looked for from small widths up, so that it holds the crossing next to the chord's (a
    // segment through both walls of a sphere has f(0) and f(1) of one sign).
    for (const double w : { 1.0 / 64, 1.0 / 16, 1.0 / 4, 1.0 })
    {
      double lo = std::max(0.0, tc - w), hi = std::min(1.0, tc + w);
      const double flo = f(lo), fhi = f(hi);
      if (!(flo * fhi <= 0.0))
        continue;
      if (flo == 0.0 || fhi == 0.0)
      {
        t = flo == 0.0 ? lo : hi;
        converged = true;
        break;
      }
      // To round-off in τ: 1100 halvings at most, in practice ~53.
      for (;;)
      {
        const double mid = 0.5 * (lo + hi);
        if (!(mid > lo && mid < hi))
          break;
        const double fm = f(mid);
        if (!std::isfinite(fm))
          break;
        if ((fm < 0.0) == (flo < 0.0))
          lo = mid;
        else
          hi = mid;
      }
      t = 0.5 * (lo + hi);
      converged = std::isfinite(f(t));
      break;
    }
  }
  if (!converged && f(0.0) > 0.0 && f(1.0) > 0.0)
  {
    // A closed surface whose chord enters it while neither Newton nor a bracket about the chord's
    // crossing finds the ray doing so: either the ray passes through both walls further off, or
    // it grazes the surface outside, where the chord cuts the corner by its sagitta. Samples along
    // the ray tell which; a ray that stays outside all along hits nothing here.
    constexpr int samples = 32;
    double lo = 0.0;
    for (int k = 1; k <= samples && !converged; ++k)
    {
      double hi = static_cast<double>(k) / samples;
      if (!(f(hi) <= 0.0))
      {
        lo = hi;
        continue;
      }
      for (int m = 0; m < 200; ++m)
      {
        const double mid = 0.5 * (lo + hi);
        if (!(mid > lo && mid < hi))
          break;
        (f(mid) > 0.0 ? lo : hi) = mid;
      }
      t = hi;
      converged = std::isfinite(f(t));
    }
    if (!converged)
      return false;
  }

  Vec3 dir = b - a;
  Vec3 x = chord;
  if (converged)
  {
    x = seg.position(t).tail<3>();
    converged = x.allFinite();
  }
  // The refined point is on the ray; the chord's lies off it by the step's sagitta, so near an
  // edge only the refined point can say whether the ray meets the finite object.
  if (!this->inBounds(converged ? x : chord))
    return false;
  hit.objectId = this->Id;
  hit.chordPoint = chord;
  hit.refined = converged;
  if (converged)
  {
    hit.tau = t;
    hit.point = x;
    const Vec3 T = seg.tangent(t).tail<3>();
    if (T.squaredNorm() > 0.0)
      dir = T;
  }
  else
  {
    hit.tau = tc;
    hit.point = chord;
  }
  this->implicit(hit.point, grad);
  const double gn = grad.norm();
  hit.normal = gn > 0.0 ? Vec3(grad / gn) : Vec3(-dir.normalized());
  if (hit.normal.dot(dir) > 0.0)
    hit.normal = -hit.normal;
  this->surfaceCoordinates(hit.point, hit.u, hit.v);
  return true;
}

// ---------------------------------------------------------------------------------------------
CelestialSphere::CelestialSphere(int id, std::string name, std::shared_ptr<const Texture> t,
                                 double radius)
  : SceneObject(id, std::move(name), std::move(t))
  , R(radius)
{
  requirePositive(radius, "celestial sphere radius");
}

bool CelestialSphere::chordHit(const Vec3& a, const Vec3& b, double& tau) const
{
  // Only the outward crossing counts, and it lies in the chord only if the chord ends outside.
  const double R2 = this->R * this->R;
  if (b.squaredNorm() < R2)
    return false;
  const Vec3 d = b - a;
  double t0, t1;
  if (!quadraticRoots(d.squaredNorm(), 2.0 * a.dot(d), a.squaredNorm() - R2, t0, t1) || !inUnit(t1))
    return false;
  tau = t1;
  return true;
}

double CelestialSphere::implicit(const Vec3& x, Vec3& grad) const
{
  // (|x|² − R²)/2R: smooth everywhere, |∇F| = 1 on the sphere.
  grad = x / this->R;
  return 0.5 * (x.squaredNorm() - this->R * this->R) / this->R;
}

void CelestialSphere::surfaceCoordinates(const Vec3& x, double& u, double& v) const
{
  u = turnFraction(x.x(), x.y());
  v = 1.0 - std::atan2(std::hypot(x.x(), x.y()), x.z()) / M_PI;
}

Vec3 CelestialSphere::surfacePoint(double u, double v) const
{
  const double phi = 2.0 * M_PI * u, theta = M_PI * (1.0 - v);
  return this->R *
         Vec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
}

// ---------------------------------------------------------------------------------------------
Rectangle::Rectangle(int id, std::string name, std::shared_ptr<const Texture> t, const Vec3& center,
                     const Vec3& uAxis, const Vec3& vAxis, double halfWidth, double halfHeight,
                     double tile)
  : SceneObject(id, std::move(name), std::move(t))
  , C(center)
  , HalfW(halfWidth)
  , HalfH(halfHeight)
  , Tile(tile)
{
  requireFinite3(center, "rectangle centre");
  this->Eu = unitAxis(uAxis, "rectangle uAxis");
  requireFinite3(vAxis, "rectangle vAxis");
  const Vec3 vp = vAxis - vAxis.dot(this->Eu) * this->Eu;
  if (!(vp.norm() > 1e-9 * vAxis.norm()))
    invalid("rectangle vAxis must not be zero or parallel to uAxis, got uAxis " + show(uAxis) +
            ", vAxis " + show(vAxis));
  this->Ev = vp.normalized();
  this->N = this->Eu.cross(this->Ev);
  // Infinite extents are allowed (a plane or a strip), NaN is not.
  if (!(halfWidth > 0.0) || !(halfHeight > 0.0))
  {
    std::ostringstream os;
    os << "rectangle half sizes must be positive, got " << halfWidth << " x " << halfHeight;
    invalid(os.str());
  }
  requirePositive(tile, "plane tile");
}

bool Rectangle::boundingSphere(Vec3& center, double& radius) const
{
  if (std::isinf(this->HalfW) || std::isinf(this->HalfH))
    return false;
  center = this->C;
  radius = std::hypot(this->HalfW, this->HalfH);
  return true;
}

double Rectangle::distanceFrom(const Vec3& x) const
{
  // Exact: the in-plane excess beyond the edges (0 along an infinite extent) and the height.
  const Vec3 w = x - this->C;
  const double du = std::max(0.0, std::abs(w.dot(this->Eu)) - this->HalfW);
  const double dv = std::max(0.0, std::abs(w.dot(this->Ev)) - this->HalfH);
  const double dn = w.dot(this->N);
  return std::sqrt(du * du + dv * dv + dn * dn);
}

bool Rectangle::chordHit(const Vec3& a, const Vec3& b, double& tau) const
{
  const Vec3 d = b - a;
  const double den = this->N.dot(d);
  if (den == 0.0)
    return false; // parallel: a chord in the plane meets it in a set of measure zero
  const double t = this->N.dot(this->C - a) / den;
  if (!inUnit(t))
    return false;
  tau = t;
  return true;
}

double Rectangle::implicit(const Vec3& x, Vec3& grad) const
{
  grad = this->N;
  return this->N.dot(x - this->C);
}

bool Rectangle::inBounds(const Vec3& x) const
{
  const Vec3 w = x - this->C;
  return std::abs(this->Eu.dot(w)) <= this->HalfW && std::abs(this->Ev.dot(w)) <= this->HalfH;
}

void Rectangle::surfaceCoordinates(const Vec3& x, double& u, double& v) const
{
  const Vec3 w = x - this->C;
  auto coordinate = [this](double s, double half)
  {
    if (std::isinf(half))
    {
      const double q = s / this->Tile;
      return q - std::floor(q);
    }
    return std::clamp(0.5 * (s + half) / half, 0.0, 1.0);
  };
  u = coordinate(this->Eu.dot(w), this->HalfW);
  v = coordinate(this->Ev.dot(w), this->HalfH);
}

Vec3 Rectangle::surfacePoint(double u, double v) const
{
  // Finite extents span 0 → 1; infinite ones repeat every tile, tile 0 starting at the centre.
  auto along = [this](double s, double half)
  { return std::isinf(half) ? s * this->Tile : (2.0 * s - 1.0) * half; };
  return this->C + along(u, this->HalfW) * this->Eu + along(v, this->HalfH) * this->Ev;
}

// ---------------------------------------------------------------------------------------------
Cylinder::Cylinder(int id, std::string name, std::shared_ptr<const Texture> t, const Vec3& base,
                   const Vec3& axis, double radius, double height)
  : SceneObject(id, std::move(name), std::move(t))
  , Base(base)
  , R(radius)
  , Height(height)
{
  requireFinite3(base, "cylinder base");
  this->Axis = unitAxis(axis, "cylinder axis");
  requirePositive(radius, "cylinder radius");
  requirePositive(height, "cylinder height");
  perpendicularBasis(this->Axis, this->Ref1, this->Ref2);
}

bool Cylinder::boundingSphere(Vec3& center, double& radius) const
{
  center = this->Base + 0.5 * this->Height * this->Axis;
  radius = std::hypot(this->R, 0.5 * this->Height);
  return true;
}

double Cylinder::distanceFrom(const Vec3& x) const
{
  // The wall lies within R of the axis segment: the distance to that segment, less R.
  const Vec3 w = x - this->Base;
  const double t = std::clamp(w.dot(this->Axis), 0.0, this->Height);
  return std::max(0.0, (w - t * this->Axis).norm() - this->R);
}

bool Cylinder::chordHit(const Vec3& a, const Vec3& b, double& tau) const
{
  // |w⊥ + τ d⊥|² = R², with ⊥ the part perpendicular to the axis; each root is kept only if its
  // height lies on the finite cylinder (an open one: the inner wall can be hit through an end).
  const Vec3 w = a - this->Base, d = b - a;
  const double wa = w.dot(this->Axis), da = d.dot(this->Axis);
  const Vec3 wp = w - wa * this->Axis, dp = d - da * this->Axis;
  double t[2];
  if (!quadraticRoots(dp.squaredNorm(), 2.0 * wp.dot(dp), wp.squaredNorm() - this->R * this->R,
                      t[0], t[1]))
    return false;
  for (const double ti : t)
  {
    const double h = wa + ti * da;
    if (inUnit(ti) && h >= 0.0 && h <= this->Height)
    {
      tau = ti;
      return true;
    }
  }
  return false;
}

double Cylinder::implicit(const Vec3& x, Vec3& grad) const
{
  const Vec3 w = x - this->Base;
  const Vec3 wp = w - w.dot(this->Axis) * this->Axis;
  grad = wp / this->R;
  return 0.5 * (wp.squaredNorm() - this->R * this->R) / this->R;
}

bool Cylinder::inBounds(const Vec3& x) const
{
  const double h = (x - this->Base).dot(this->Axis);
  return h >= 0.0 && h <= this->Height;
}

void Cylinder::surfaceCoordinates(const Vec3& x, double& u, double& v) const
{
  const Vec3 w = x - this->Base;
  u = turnFraction(w.dot(this->Ref1), w.dot(this->Ref2));
  v = std::clamp(w.dot(this->Axis) / this->Height, 0.0, 1.0);
}

Vec3 Cylinder::surfacePoint(double u, double v) const
{
  const double phi = 2.0 * M_PI * u;
  return this->Base + v * this->Height * this->Axis +
         this->R * (std::cos(phi) * this->Ref1 + std::sin(phi) * this->Ref2);
}

// ---------------------------------------------------------------------------------------------
Sphere::Sphere(int id, std::string name, std::shared_ptr<const Texture> t, const Vec3& center,
               double radius)
  : SceneObject(id, std::move(name), std::move(t))
  , C(center)
  , R(radius)
{
  requireFinite3(center, "sphere centre");
  requirePositive(radius, "sphere radius");
}

bool Sphere::boundingSphere(Vec3& center, double& radius) const
{
  center = this->C;
  radius = this->R;
  return true;
}

double Sphere::distanceFrom(const Vec3& x) const
{
  return std::abs((x - this->C).norm() - this->R);
}

bool Sphere::chordHit(const Vec3& a, const Vec3& b, double& tau) const
{
  const Vec3 w = a - this->C, d = b - a;
  double t0, t1;
  if (!quadraticRoots(d.squaredNorm(), 2.0 * w.dot(d), w.squaredNorm() - this->R * this->R, t0, t1))
    return false;
  if (inUnit(t0))
    tau = t0;
  else if (inUnit(t1))
    tau = t1; // the chord starts inside
  else
    return false;
  return true;
}

double Sphere::implicit(const Vec3& x, Vec3& grad) const
{
  const Vec3 w = x - this->C;
  grad = w / this->R;
  return 0.5 * (w.squaredNorm() - this->R * this->R) / this->R;
}

void Sphere::surfaceCoordinates(const Vec3& x, double& u, double& v) const
{
  const Vec3 w = x - this->C;
  u = turnFraction(w.x(), w.y());
  v = 1.0 - std::atan2(std::hypot(w.x(), w.y()), w.z()) / M_PI;
}

Vec3 Sphere::surfacePoint(double u, double v) const
{
  const double phi = 2.0 * M_PI * u, theta = M_PI * (1.0 - v);
  return this->C + this->R * Vec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                                  std::cos(theta));
}

// ---------------------------------------------------------------------------------------------
Disk::Disk(int id, std::string name, std::shared_ptr<const Texture> t, const Vec3& center,
           const Vec3& normal, double innerRadius, double outerRadius)
  : SceneObject(id, std::move(name), std::move(t))
  , C(center)
  , Rin(innerRadius)
  , Rout(outerRadius)
{
  requireFinite3(center, "disk centre");
  this->N = unitAxis(normal, "disk normal");
  if (!(std::isfinite(innerRadius) && innerRadius >= 0.0))
  {
    std::ostringstream os;
    os << "disk inner radius must be finite and non-negative, got " << innerRadius;
    invalid(os.str());
  }
  if (!(std::isfinite(outerRadius) && outerRadius > innerRadius))
  {
    std::ostringstream os;
    os << "disk outer radius must be finite and above the inner radius " << innerRadius << ", got "
       << outerRadius;
    invalid(os.str());
  }
  perpendicularBasis(this->N, this->Ref1, this->Ref2);
}

bool Disk::boundingSphere(Vec3& center, double& radius) const
{
  center = this->C;
  radius = this->Rout;
  return true;
}

double Disk::distanceFrom(const Vec3& x) const
{
  // Exact: the height above the plane and the radial distance outside the annulus.
  const Vec3 w = x - this->C;
  const double dn = w.dot(this->N);
  const double rho = (w - dn * this->N).norm();
  const double dr = rho > this->Rout ? rho - this->Rout : (rho < this->Rin ? this->Rin - rho : 0.0);
  return std::sqrt(dn * dn + dr * dr);
}

bool Disk::chordHit(const Vec3& a, const Vec3& b, double& tau) const
{
  const Vec3 d = b - a;
  const double den = this->N.dot(d);
  if (den == 0.0)
    return false;
  const double t = this->N.dot(this->C - a) / den;
  if (!inUnit(t))
    return false;
  tau = t;
  return true;
}

double Disk::implicit(const Vec3& x, Vec3& grad) const
{
  grad = this->N;
  return this->N.dot(x - this->C);
}

bool Disk::inBounds(const Vec3& x) const
{
  const Vec3 w = x - this->C;
  const double rho2 = (w - w.dot(this->N) * this->N).squaredNorm();
  return rho2 >= this->Rin * this->Rin && rho2 <= this->Rout * this->Rout;
}

void Disk::surfaceCoordinates(const Vec3& x, double& u, double& v) const
{
  const Vec3 w = x - this->C;
  const double c1 = w.dot(this->Ref1), c2 = w.dot(this->Ref2);
  u = turnFraction(c1, c2);
  v = std::clamp((std::hypot(c1, c2) - this->Rin) / (this->Rout - this->Rin), 0.0, 1.0);
}

Vec3 Disk::surfacePoint(double u, double v) const
{
  const double phi = 2.0 * M_PI * u, r = this->Rin + v * (this->Rout - this->Rin);
  return this->C + r * (std::cos(phi) * this->Ref1 + std::sin(phi) * this->Ref2);
}

// ---------------------------------------------------------------------------------------------
struct Scene::LazyHierarchy
{
  std::mutex lock;
  std::atomic<bool> built{ false };
  ObjectHierarchy tree;
};

Scene::Scene()
  : Hierarchy(std::make_unique<LazyHierarchy>())
{
}

Scene::~Scene() = default;

Scene::Scene(Scene&& other)
  : Scene()
{
  *this = std::move(other);
}

Scene& Scene::operator=(Scene&& other)
{
  if (this != &other)
  {
    this->background = other.background;
    this->horizonColor = other.horizonColor;
    this->Objects = std::move(other.Objects);
    this->Bounds = std::move(other.Bounds);
    this->Unbounded = std::move(other.Unbounded);
    this->DenseIndex = std::move(other.DenseIndex);
    this->SparseIndex = std::move(other.SparseIndex);
    std::swap(this->Hierarchy, other.Hierarchy);
    other.Objects.clear();
    other.Bounds.clear();
    other.Unbounded.clear();
    other.DenseIndex.clear();
    other.SparseIndex.clear();
    other.Hierarchy->built.store(false);
  }
  return *this;
}

const ObjectHierarchy& Scene::hierarchy() const
{
  // Double-checked: readers of a built hierarchy take no lock; add() clears `built` and is never
  // concurrent with queries (it is not const).
  LazyHierarchy& h = *this->Hierarchy;
  if (!h.built.load(std::memory_order_acquire))
  {
    std::lock_guard<std::mutex> guard(h.lock);
    if (!h.built.load(std::memory_order_relaxed))
    {
      std::vector<ObjectHierarchy::Ball> balls;
      for (std::size_t k = 0; k < this->Bounds.size(); ++k)
      {
        if (this->Bounds[k].finite)
          balls.push_back(
            { static_cast<std::uint32_t>(k), this->Bounds[k].center, this->Bounds[k].radius });
      }
      h.tree.build(std::move(balls));
      h.built.store(true, std::memory_order_release);
    }
  }
  return h.tree;
}

void Scene::add(std::unique_ptr<SceneObject> object)
{
  if (!object)
    invalid("cannot add a null object to a scene");
  if (const SceneObject* other = this->find(object->id()))
  {
    invalid("object id " + std::to_string(object->id()) + " (\"" + object->name() +
            "\") is already used by \"" + other->name() + "\"");
  }
  Bound bound;
  bound.finite = object->boundingSphere(bound.center, bound.radius);
  bound.sky = dynamic_cast<const CelestialSphere*>(object.get()) != nullptr;
  const int id = object->id();
  const std::size_t index = this->Objects.size();
  if (id < kDenseIds)
  {
    if (static_cast<std::size_t>(id) >= this->DenseIndex.size())
      this->DenseIndex.resize(id + 1, -1);
    this->DenseIndex[id] = static_cast<int>(index);
  }
  else
    this->SparseIndex.emplace(id, index);
  if (!bound.finite)
    this->Unbounded.push_back(index);
  this->Bounds.push_back(bound);
  this->Objects.push_back(std::move(object));
  this->Hierarchy->built.store(false, std::memory_order_release);
}

const SceneObject* Scene::find(int id) const
{
  if (id < 0)
    return nullptr;
  if (id < kDenseIds)
  {
    if (static_cast<std::size_t>(id) >= this->DenseIndex.size() || this->DenseIndex[id] < 0)
      return nullptr;
    return this->Objects[this->DenseIndex[id]].get();
  }
  const auto it = this->SparseIndex.find(id);
  return it == this->SparseIndex.end() ? nullptr : this->Objects[it->second].get();
}

bool Scene::firstHit(const Segment& seg, SurfaceHit& hit) const
{
  const Vec3 a = seg.x0.tail<3>(), b = seg.x1.tail<3>();
  const Vec3 mid = 0.5 * (a + b);
  const double half = 0.5 * (b - a).norm();
  bool found = false;
  std::size_t foundIndex = 0;
  SurfaceHit candidate;
  auto test = [&](std::size_t k)
  {
    const Bound& bound = this->Bounds[k];
    if (seg.farField && !bound.sky)
      return; // the segment lies outside every other object's reach
    if (bound.finite)
    {
      // The chord lies in the ball of radius `half` about its midpoint; the margin absorbs
      // round-off for chords that touch the object.
      const double reach = (bound.radius + half) * (1.0 + 1e-9);
      if ((mid - bound.center).squaredNorm() > reach * reach ||
          this->Objects[k]->distanceFrom(mid) > half * (1.0 + 1e-9) + 1e-12 * (1.0 + half))
        return;
    }
    // Objects come in no particular order: on equal τ the lower index wins, as in index order.
    if (this->Objects[k]->intersect(seg, candidate) &&
        (!found || candidate.tau < hit.tau || (candidate.tau == hit.tau && k < foundIndex)))
    {
      hit = candidate;
      foundIndex = k;
      found = true;
    }
  };
  for (const std::size_t k : this->Unbounded)
    test(k);
  if (seg.farField)
    return found; // no bounded object is a celestial sphere
  // The interpolant less the chord is Σ basis × (end tangent − chord, end acceleration), the basis
  // functions of the tangents bounded by 0.2 on [0, 1] (quintic; 4/27 cubic), those of the
  // accelerations by 0.0174: a hit lies within `bend` of the chord.
  ObjectHierarchy::Chord chord;
  chord.a = a;
  chord.b = b;
  chord.mid = mid;
  chord.half = half;
  const Vec3 delta = b - a;
  chord.bend = 0.25 * ((seg.d0.tail<3>() - delta).norm() + (seg.d1.tail<3>() - delta).norm());
  if (seg.quintic)
    chord.bend += 0.025 * (seg.a0.tail<3>().norm() + seg.a1.tail<3>().norm());
  this->hierarchy().visitNear(chord, test);
  return found;
}

Color Scene::shade(int objectId, double u, double v) const
{
  const SceneObject* o = this->find(objectId);
  return o ? o->texture().sample(u, v) : this->background;
}

Color Scene::shadeFootprint(int objectId, double u, double v, const TextureFootprint& f) const
{
  const SceneObject* o = this->find(objectId);
  return o ? o->texture().sampleFootprint(u, v, f) : this->background;
}

double Scene::celestialRadius() const
{
  double r = 0.0;
  for (const auto& o : this->Objects)
  {
    if (const auto* sky = dynamic_cast<const CelestialSphere*>(o.get()))
      r = std::max(r, sky->radius());
  }
  return r;
}

double Scene::objectDistance(const Vec3& x) const
{
  double d = std::numeric_limits<double>::infinity();
  for (const std::size_t k : this->Unbounded)
  {
    if (!this->Bounds[k].sky)
      d = std::min(d, this->Objects[k]->distanceFrom(x));
  }
  // The ball's distance bounds the object's as distanceFrom does, and may be the tighter (a
  // cylinder's bound, from its axis segment less its radius, falls below its ball's beyond its
  // ends). Taking the larger lets the hierarchy prune by box distance, which is below the ball's.
  auto bounded = [this, &x](std::size_t k)
  {
    const Bound& bound = this->Bounds[k];
    const double ball = std::max(0.0, (x - bound.center).norm() - bound.radius);
    return std::max(this->Objects[k]->distanceFrom(x), ball);
  };
  return this->hierarchy().minimum(x, d, bounded);
}

FarField Scene::farField() const
{
  FarField far;
  far.objectDistance = [this](const Vec3& x) { return this->objectDistance(x); };
  far.objectRadius = 0.0;
  for (std::size_t k = 0; k < this->Objects.size(); ++k)
  {
    const Bound& bound = this->Bounds[k];
    if (bound.sky)
      far.skyRadii.push_back(static_cast<const CelestialSphere&>(*this->Objects[k]).radius());
    else if (!bound.finite)
      far.objectRadius = std::numeric_limits<double>::infinity();
    else
      far.objectRadius = std::max(far.objectRadius, bound.center.norm() + bound.radius);
  }
  std::sort(far.skyRadii.begin(), far.skyRadii.end());
  return far;
}
}
