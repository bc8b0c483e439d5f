// Scene objects that rays can hit, each with an id, a name and surface coordinates (u, v), and the
// scene that finds a segment's first hit and colours it (the textures are in Texture.h). Plain C++
// on Eigen.
#ifndef asrt_Scene_h
#define asrt_Scene_h

#include "Propagator.h"
#include "Texture.h"
#include "asrtTracingModule.h"

#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

namespace asrt
{
/// Where a ray's segment meets an object.
struct SurfaceHit
{
  int objectId = -1;
  double tau = 0;                 ///< step fraction of the hit, refined on the interpolant
  Vec3 point = Vec3::Zero();      ///< refined hit point
  Vec3 chordPoint = Vec3::Zero(); ///< the straight chord's hit, before refinement
  Vec3 normal = Vec3::Zero();     ///< unit surface normal at the hit, facing the arriving ray
  double u = 0, v = 0;            ///< surface coordinates ∈ [0, 1]
  bool refined = false;           ///< false: refinement failed or left the object, chord hit kept
};

class ASRTTRACING_EXPORT SceneObject
{
public:
  /// Throws InvalidParameter for a negative id (−1 means "no object" in a SurfaceHit) or a null
  /// texture.
  SceneObject(int id, std::string name, std::shared_ptr<const Texture> texture);
  virtual ~SceneObject() = default;
  int id() const { return this->Id; }
  const std::string& name() const { return this->Name; }
  virtual const char* type() const = 0;

  /// First crossing of the segment with the object: the chord x0 → x1 finds a crossing of the
  /// object's surface (as the paper does), which is refined on the segment's Hermite interpolant
  /// so that the hit's error is the integrator's, not the chord's (Newton on F(x(τ)), bisection if
  /// Newton cannot step). Whether the hit lies on the finite object is judged at the refined
  /// point, since that point is on the ray and the chord's is not: a curve crossing beyond an edge
  /// is a miss even where its chord crosses inside, and the converse is a hit. Only if refinement
  /// fails is the chord's point judged and kept (hit.refined = false). Thread-safe; allocates
  /// nothing.
  bool intersect(const Segment& seg, SurfaceHit& hit) const;
  Color color(const SurfaceHit& hit) const { return this->Tex->sample(hit.u, hit.v); }
  const Texture& texture() const { return *this->Tex; }
  /// The inverse of the surface coordinates: the point at (u, v) ∈ [0, 1]², for drawing the
  /// object. Infinite planes repeat every tile; (u, v) outside [0, 1] reach the further tiles.
  virtual Vec3 surfacePoint(double u, double v) const = 0;
  /// True for objects without bounds (infinite planes).
  virtual bool isInfinite() const { return false; }
  /// A ball containing the object, for cheap rejection; false if the object is unbounded (or, like
  /// the celestial sphere, rejects segments cheaply itself).
  virtual bool boundingSphere(Vec3& center, double& radius) const = 0;
  /// A lower bound on the distance from x to the object (0 on it): no chord in the ball of that
  /// radius about x can meet it. The default is the bounding sphere's (0 if there is none); the
  /// finite objects give the exact distance or a tight bound.
  virtual double distanceFrom(const Vec3& x) const;

protected:
  /// Smallest τ ∈ [0, 1] at which the chord a + τ(b − a) meets the surface. Planar objects test
  /// their whole plane (their bounds are judged on the refined point); curved ones may reject
  /// crossings off their bounds here, as a cylinder does to pick the wall that is hit.
  virtual bool chordHit(const Vec3& a, const Vec3& b, double& tau) const = 0;
  /// A function vanishing on the surface, with its gradient (for Newton refinement). |∇F| = 1 on
  /// the surface, so that F near it is a signed distance and tolerances are lengths.
  virtual double implicit(const Vec3& x, Vec3& grad) const = 0;
  /// Whether a point on the (infinite) implicit surface lies on the finite object.
  virtual bool inBounds(const Vec3& x) const = 0;
  virtual void surfaceCoordinates(const Vec3& x, double& u, double& v) const = 0;

private:
  int Id;
  std::string Name;
  std::shared_ptr<const Texture> Tex;
};

/// The sky: a sphere of finite radius about the origin, seen from inside (only crossings from
/// inside to outside count). Equirectangular: u = φ/2π with φ = atan2(y, x) ∈ [0, 2π), v = 1 − θ/π
/// with θ from +z, so v = 1 at the north pole and an image's top row (as displayed) is the sky's
/// top.
class ASRTTRACING_EXPORT CelestialSphere final : public SceneObject
{
public:
  Vec3 surfacePoint(double u, double v) const override;
  CelestialSphere(int id, std::string name, std::shared_ptr<const Texture> t, double radius);
  const char* type() const override { return "celestialSphere"; }
  double radius() const { return this->R; }
  bool boundingSphere(Vec3&, double&) const override { return false; }

protected:
  bool chordHit(const Vec3& a, const Vec3& b, double& tau) const override;
  double implicit(const Vec3& x, Vec3& grad) const override;
  bool inBounds(const Vec3&) const override { return true; }
  void surfaceCoordinates(const Vec3& x, double& u, double& v) const override;

private:
  double R;
};

/// A rectangle (halfWidth, halfHeight finite) or an infinite plane (both infinite) through
/// `center`, spanned by the orthonormalised axes `uAxis` and `vAxis` (vAxis is made orthogonal to
/// uAxis; the normal is uAxis × vAxis). Along a finite extent u (or v) runs 0 → 1 from −half to
/// +half; along an infinite one it repeats every `tile` M, u = 0 at `center`.
class ASRTTRACING_EXPORT Rectangle final : public SceneObject
{
public:
  Vec3 surfacePoint(double u, double v) const override;
  bool isInfinite() const override { return std::isinf(this->HalfW) || std::isinf(this->HalfH); }
  double distanceFrom(const Vec3& x) const override;
  Rectangle(int id, std::string name, std::shared_ptr<const Texture> t, const Vec3& center,
            const Vec3& uAxis, const Vec3& vAxis, double halfWidth, double halfHeight,
            double tile = 1.0);
  const char* type() const override
  {
    return std::isinf(this->HalfW) && std::isinf(this->HalfH) ? "plane" : "rectangle";
  }
  bool boundingSphere(Vec3& center, double& radius) const override;

protected:
  bool chordHit(const Vec3& a, const Vec3& b, double& tau) const override;
  double implicit(const Vec3& x, Vec3& grad) const override;
  bool inBounds(const Vec3& x) const override;
  void surfaceCoordinates(const Vec3& x, double& u, double& v) const override;

private:
  Vec3 C, Eu, Ev, N;
  double HalfW, HalfH, Tile;
};

/// A finite open cylinder (no caps): axis from `base` along `axis` (normalised) for `height`;
/// u = angle/2π around the axis, measured from the reference direction perpendicular to the axis
/// (see perpendicularBasis), v = height fraction.
class ASRTTRACING_EXPORT Cylinder final : public SceneObject
{
public:
  Vec3 surfacePoint(double u, double v) const override;
  Cylinder(int id, std::string name, std::shared_ptr<const Texture> t, const Vec3& base,
           const Vec3& axis, double radius, double height);
  const char* type() const override { return "cylinder"; }
  bool boundingSphere(Vec3& center, double& radius) const override;
  double distanceFrom(const Vec3& x) const override;

protected:
  bool chordHit(const Vec3& a, const Vec3& b, double& tau) const override;
  double implicit(const Vec3& x, Vec3& grad) const override;
  bool inBounds(const Vec3& x) const override;
  void surfaceCoordinates(const Vec3& x, double& u, double& v) const override;

private:
  Vec3 Base, Axis, Ref1, Ref2;
  double R, Height;
};

/// A sphere, hit from outside or inside; u = φ/2π, v = 1 − θ/π about its centre (θ from +z), as
/// for the celestial sphere.
class ASRTTRACING_EXPORT Sphere final : public SceneObject
{
public:
  Vec3 surfacePoint(double u, double v) const override;
  Sphere(int id, std::string name, std::shared_ptr<const Texture> t, const Vec3& center,
         double radius);
  const char* type() const override { return "sphere"; }
  bool boundingSphere(Vec3& center, double& radius) const override;
  double distanceFrom(const Vec3& x) const override;

protected:
  bool chordHit(const Vec3& a, const Vec3& b, double& tau) const override;
  double implicit(const Vec3& x, Vec3& grad) const override;
  bool inBounds(const Vec3&) const override { return true; }
  void surfaceCoordinates(const Vec3& x, double& u, double& v) const override;

private:
  Vec3 C;
  double R;
};

/// A thin annulus through `center` with `normal` (normalised), inner radius ≥ 0 (0: a full disk)
/// below the outer one; u = angle/2π about the normal from the reference direction (see
/// perpendicularBasis), v = (r − inner)/(outer − inner).
class ASRTTRACING_EXPORT Disk final : public SceneObject
{
public:
  Vec3 surfacePoint(double u, double v) const override;
  Disk(int id, std::string name, std::shared_ptr<const Texture> t, const Vec3& center,
       const Vec3& normal, double innerRadius, double outerRadius);
  const char* type() const override { return "disk"; }
  bool boundingSphere(Vec3& center, double& radius) const override;
  double distanceFrom(const Vec3& x) const override;

protected:
  bool chordHit(const Vec3& a, const Vec3& b, double& tau) const override;
  double implicit(const Vec3& x, Vec3& grad) const override;
  bool inBounds(const Vec3& x) const override;
  void surfaceCoordinates(const Vec3& x, double& u, double& v) const override;

private:
  Vec3 C, N, Ref1, Ref2;
  double Rin, Rout;
};

/// Orthonormal e1, e2 completing the unit vector n to a right-handed frame (e1 × e2 = n): e1 is the
/// coordinate axis least aligned with n (x before y before z on ties), made orthogonal to n. For
/// n = +z this is (x̂, ŷ), so angles about +z are the usual φ.
ASRTTRACING_EXPORT void perpendicularBasis(const Vec3& n, Vec3& e1, Vec3& e2);

class ObjectHierarchy;

/// The objects of a scene. Ids are unique; the first hit along a segment is the one with the
/// smallest τ. The bounded objects are searched through a bounding-volume hierarchy over their
/// bounding balls, built at the first query after objects were added.
class ASRTTRACING_EXPORT Scene
{
public:
  Scene();
  ~Scene();
  /// The moved-from scene is left empty.
  Scene(Scene&& other);
  Scene& operator=(Scene&& other);
  /// Throws InvalidParameter for a null object or if an object with the same id is already there.
  void add(std::unique_ptr<SceneObject> object);
  const std::vector<std::unique_ptr<SceneObject>>& objects() const { return this->Objects; }
  /// The object with this id, nullptr if none. O(1): an index cached at add().
  const SceneObject* find(int id) const;
  /// The nearest hit along the segment over all objects; on equal τ the object added first. Each
  /// object is tested as if alone (its bounding ball, its distance from the chord's midpoint, then
  /// its intersection), but only those the hierarchy cannot rule out (a box out of the chord's
  /// ball's reach, or farther from the chord than the interpolant strays): the answer is the one a
  /// loop over every object gives. Thread-safe and allocation-free once the hierarchy is
  /// built (the first query builds it, under a lock).
  bool firstHit(const Segment& seg, SurfaceHit& hit) const;
  /// The hit object's colour at the hit; the background if the id is unknown.
  Color shade(const SurfaceHit& hit) const { return this->shade(hit.objectId, hit.u, hit.v); }
  /// The object's texture sampled at (u, v); the background if the id is unknown. Thread-safe,
  /// allocation-free, O(1).
  Color shade(int objectId, double u, double v) const;
  /// The object's texture averaged over the footprint about (u, v) (Texture::sampleFootprint: a
  /// box filter over the pixel; a non-finite footprint gives the point sample); the background if
  /// the id is unknown. Thread-safe, allocation-free, O(1).
  Color shadeFootprint(int objectId, double u, double v, const TextureFootprint& f) const;
  Color background = Color(0, 0, 0);   ///< for rays that escape without hitting anything
  Color horizonColor = Color(0, 0, 0); ///< for rays captured by the hole
  /// The colour of a ray that hit nothing: the horizon's if the hole captured it, the background
  /// if it escaped, else (the integrator lost it) magenta, a diagnostic colour of no real scene.
  Color endColor(Termination t) const
  {
    return t == Termination::Captured  ? this->horizonColor
           : t == Termination::Escaped ? this->background
                                       : Color(1.0, 0.0, 1.0);
  }
  /// Radius of the largest celestial sphere, 0 if none: rays farther out can hit nothing.
  double celestialRadius() const;
  /// The far field of this scene about the origin: the radius of the smallest ball about the origin
  /// that holds every object but the celestial spheres (infinite if one is unbounded, 0 if there
  /// are none), the celestial spheres' radii, ascending, and objectDistance, which refers to this
  /// scene: the scene must outlive the FarField.
  FarField farField() const;
  /// A lower bound on the distance from x to every object but the celestial spheres (infinite if
  /// there are none): the least over those objects of max(distanceFrom(x), the distance from x to
  /// the object's bounding ball), both lower bounds on the object's distance (an unbounded object
  /// has only the first). Bounded objects are searched through the hierarchy; the result is that
  /// minimum exactly. Thread-safe and allocation-free once the hierarchy is built.
  double objectDistance(const Vec3& x) const;

private:
  /// Bounding balls cached at add(), so that rejection costs no virtual call.
  struct Bound
  {
    Vec3 center = Vec3::Zero();
    double radius = 0;
    bool finite = false;
    bool sky = false; ///< a celestial sphere: the only object a far-field segment can hit
  };
  /// Ids below this index Objects through a vector, larger ones through a hash map, so that
  /// sparse ids up to INT_MAX cost memory only for the ids used.
  static constexpr int kDenseIds = 4096;
  std::vector<std::unique_ptr<SceneObject>> Objects;
  std::vector<Bound> Bounds;
  /// Indices of the objects without a bounding ball (celestial spheres, planes, strips), ascending:
  /// they are tested one by one.
  std::vector<std::size_t> Unbounded;
  /// The hierarchy over the bounded objects, built on demand behind a lock.
  struct LazyHierarchy;
  std::unique_ptr<LazyHierarchy> Hierarchy;
  const ObjectHierarchy& hierarchy() const;
  std::vector<int> DenseIndex; ///< id → index into Objects, −1 for none
  std::unordered_map<int, std::size_t> SparseIndex;
};
}

#endif
