// Spacetimes as Hamiltonians H(x, p) = ½ g^{μν}(x) p_μ p_ν for null geodesics.
//
// All spacetimes share one Cartesian chart (t, x, y, z): Minkowski's, and the Kerr–Schild form
// g^{μν} = η^{μν} − f l^μ l^ν of the others. That chart is horizon-penetrating and lets scene
// objects (planes, cylinders, spheres) be intersected in plain Cartesian geometry.
#ifndef asrt_Spacetime_h
#define asrt_Spacetime_h

#include "AsrtTypes.h"
#include "SpacetimeParameters.h"
#include "asrtPhysicsModule.h"

#include <memory>
#include <optional>
#include <string>

namespace asrt
{
/// What a stepping rule sees: a scalar function on phase space with its gradient.
class ASRTPHYSICS_EXPORT HamiltonianSystem
{
public:
  virtual ~HamiltonianSystem() = default;
  virtual double value(const Vec4& x, const Vec4& p) const = 0;
  /// Returns the value and writes both partial derivatives.
  virtual double gradient(const Vec4& x, const Vec4& p, Vec4& dHdx, Vec4& dHdp) const = 0;
};

enum class SpacetimeKind
{
  Minkowski,
  Schwarzschild,
  Kerr,
  ReissnerNordstrom
};

/// Radii of the circular photon orbits in the equatorial plane. They coincide (the photon sphere)
/// for spherically symmetric spacetimes.
struct PhotonOrbitRadii
{
  double prograde = 0;
  double retrograde = 0;
};

class ASRTPHYSICS_EXPORT Spacetime : public HamiltonianSystem
{
public:
  virtual SpacetimeKind kind() const = 0;
  virtual std::string name() const = 0;
  double mass() const { return this->Mass; }
  virtual double spin() const { return 0.0; }
  virtual double charge() const { return 0.0; }

  /// The radial coordinate r (areal for spherical spacetimes, Boyer–Lindquist r for Kerr).
  virtual double radius(const Vec4& x) const = 0;
  /// r and its gradient ∂r/∂x^μ (zero time component).
  virtual double radiusGradient(const Vec4& x, Vec4& grad) const = 0;

  /// H with its gradient and r with its gradient together, for time transformations: spacetimes
  /// whose r is costly (Kerr) compute it once.
  virtual double gradientAndRadius(const Vec4& x, const Vec4& p, Vec4& dHdx, Vec4& dHdp, double& r,
                                   Vec4& dr) const
  {
    r = this->radiusGradient(x, dr);
    return this->gradient(x, p, dHdx, dHdp);
  }

  virtual Mat4 inverseMetric(const Vec4& x) const = 0;
  virtual Mat4 metric(const Vec4& x) const = 0;

  /// Outer (event) horizon r_+; 0 when there is none.
  virtual double outerHorizon() const = 0;
  /// Inner (Cauchy) horizon r_-; 0 when there is none.
  virtual double innerHorizon() const { return 0.0; }
  /// Circular photon orbits; empty for flat space.
  virtual std::optional<PhotonOrbitRadii> photonOrbits() const = 0;
  /// Critical impact parameter b_c of the photon sphere (spherical spacetimes), 0 if none.
  virtual double criticalImpactParameter() const { return 0.0; }
  bool isFlat() const { return this->kind() == SpacetimeKind::Minkowski; }

protected:
  explicit Spacetime(double mass)
    : Mass(mass)
  {
  }
  double Mass;
};

/// Flat space (M = 0). Rays are straight lines; tracers solve them analytically.
class ASRTPHYSICS_EXPORT MinkowskiSpacetime final : public Spacetime
{
public:
  MinkowskiSpacetime()
    : Spacetime(0.0)
  {
  }
  SpacetimeKind kind() const override { return SpacetimeKind::Minkowski; }
  std::string name() const override { return "Minkowski"; }
  double value(const Vec4& x, const Vec4& p) const override { return hamiltonian<double>(x, p); }
  double gradient(const Vec4& x, const Vec4& p, Vec4& dHdx, Vec4& dHdp) const override;
  double radius(const Vec4& x) const override { return x.tail<3>().norm(); }
  double radiusGradient(const Vec4& x, Vec4& grad) const override;
  Mat4 inverseMetric(const Vec4& x) const override;
  Mat4 metric(const Vec4& x) const override;
  double outerHorizon() const override { return 0.0; }
  std::optional<PhotonOrbitRadii> photonOrbits() const override { return std::nullopt; }

  template<class S>
  static S hamiltonian(const Eigen::Matrix<S, 4, 1>&, const Eigen::Matrix<S, 4, 1>& p)
  {
    return S(0.5) * (-p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3]);
  }
};

/// Schwarzschild in Kerr–Schild Cartesian form: f = 2M/r, l^μ = (−1, x/r, y/r, z/r).
/// It pays for none of Kerr's terms: r = |x| and no spin cross-terms.
class ASRTPHYSICS_EXPORT SchwarzschildSpacetime final : public Spacetime
{
public:
  explicit SchwarzschildSpacetime(double mass);
  SpacetimeKind kind() const override { return SpacetimeKind::Schwarzschild; }
  std::string name() const override { return "Schwarzschild"; }
  double value(const Vec4& x, const Vec4& p) const override { return hamiltonian<double>(x, p); }
  double gradient(const Vec4& x, const Vec4& p, Vec4& dHdx, Vec4& dHdp) const override;
  double gradientAndRadius(const Vec4& x, const Vec4& p, Vec4& dHdx, Vec4& dHdp, double& r,
                           Vec4& dr) const override;
  double radius(const Vec4& x) const override { return x.tail<3>().norm(); }
  double radiusGradient(const Vec4& x, Vec4& grad) const override;
  Mat4 inverseMetric(const Vec4& x) const override;
  Mat4 metric(const Vec4& x) const override;
  double outerHorizon() const override { return 2.0 * this->Mass; }
  std::optional<PhotonOrbitRadii> photonOrbits() const override;
  double criticalImpactParameter() const override;

  template<class S>
  S hamiltonian(const Eigen::Matrix<S, 4, 1>& x, const Eigen::Matrix<S, 4, 1>& p) const
  {
    using std::sqrt;
    const S r = sqrt(x[1] * x[1] + x[2] * x[2] + x[3] * x[3]);
    const S s = -p[0] + (x[1] * p[1] + x[2] * p[2] + x[3] * p[3]) / r;
    const S f = S(2.0 * this->Mass) / r;
    return S(0.5) * (-p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3] - f * s * s);
  }
};

/// Reissner–Nordström (charge Q) in Kerr–Schild form: f = 2M/r − Q²/r² (Kerr–Newman at a = 0).
class ASRTPHYSICS_EXPORT ReissnerNordstromSpacetime final : public Spacetime
{
public:
  ReissnerNordstromSpacetime(double mass, double charge);
  SpacetimeKind kind() const override { return SpacetimeKind::ReissnerNordstrom; }
  std::string name() const override { return "Reissner-Nordstrom"; }
  double charge() const override { return this->Charge; }
  double value(const Vec4& x, const Vec4& p) const override { return hamiltonian<double>(x, p); }
  double gradient(const Vec4& x, const Vec4& p, Vec4& dHdx, Vec4& dHdp) const override;
  double gradientAndRadius(const Vec4& x, const Vec4& p, Vec4& dHdx, Vec4& dHdp, double& r,
                           Vec4& dr) const override;
  double radius(const Vec4& x) const override { return x.tail<3>().norm(); }
  double radiusGradient(const Vec4& x, Vec4& grad) const override;
  Mat4 inverseMetric(const Vec4& x) const override;
  Mat4 metric(const Vec4& x) const override;
  double outerHorizon() const override;
  double innerHorizon() const override;
  std::optional<PhotonOrbitRadii> photonOrbits() const override;
  double criticalImpactParameter() const override;

  template<class S>
  S hamiltonian(const Eigen::Matrix<S, 4, 1>& x, const Eigen::Matrix<S, 4, 1>& p) const
  {
    using std::sqrt;
    const S r = sqrt(x[1] * x[1] + x[2] * x[2] + x[3] * x[3]);
    const S s = -p[0] + (x[1] * p[1] + x[2] * p[2] + x[3] * p[3]) / r;
    const S f = S(2.0 * this->Mass) / r - S(this->Charge * this->Charge) / (r * r);
    return S(0.5) * (-p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3] - f * s * s);
  }

private:
  double Charge;
};

/// Kerr (spin a along +z) in Kerr–Schild Cartesian form (physics.md):
/// f = 2Mr³/(r⁴ + a²z²), l_μ = (1, (rx + ay)/(r² + a²), (ry − ax)/(r² + a²), z/r).
class ASRTPHYSICS_EXPORT KerrSpacetime final : public Spacetime
{
public:
  KerrSpacetime(double mass, double spin);
  SpacetimeKind kind() const override { return SpacetimeKind::Kerr; }
  std::string name() const override { return "Kerr"; }
  double spin() const override { return this->Spin; }
  double value(const Vec4& x, const Vec4& p) const override { return hamiltonian<double>(x, p); }
  double gradient(const Vec4& x, const Vec4& p, Vec4& dHdx, Vec4& dHdp) const override;
  double gradientAndRadius(const Vec4& x, const Vec4& p, Vec4& dHdx, Vec4& dHdp, double& r,
                           Vec4& dr) const override;
  double radius(const Vec4& x) const override;
  double radiusGradient(const Vec4& x, Vec4& grad) const override;
  Mat4 inverseMetric(const Vec4& x) const override;
  Mat4 metric(const Vec4& x) const override;
  double outerHorizon() const override;
  double innerHorizon() const override;
  std::optional<PhotonOrbitRadii> photonOrbits() const override;
  /// Outer boundary of the ergosphere, r_E = M + √(M² − a² cos²θ).
  double ergosphereRadius(double cosTheta) const;

  template<class S>
  S hamiltonian(const Eigen::Matrix<S, 4, 1>& x, const Eigen::Matrix<S, 4, 1>& p) const
  {
    using std::sqrt;
    const double a = this->Spin;
    const S R2 = x[1] * x[1] + x[2] * x[2] + x[3] * x[3];
    const S h = S(0.5) * (R2 - a * a);
    const S r2 = h + sqrt(h * h + S(a * a) * x[3] * x[3]);
    const S r = sqrt(r2);
    const S D = r2 + a * a;
    const S lx = (r * x[1] + a * x[2]) / D;
    const S ly = (r * x[2] - a * x[1]) / D;
    const S lz = x[3] / r;
    const S s = -p[0] + lx * p[1] + ly * p[2] + lz * p[3];
    const S f = S(2.0 * this->Mass) * r2 * r / (r2 * r2 + S(a * a) * x[3] * x[3]);
    return S(0.5) * (-p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3] - f * s * s);
  }

private:
  double gradientAt(const Vec4& x, const Vec4& p, double r, Vec4& dHdx, Vec4& dHdp) const;
  double Spin;
};

/// The cheapest spacetime that models (M, a, Q): Minkowski for M = 0, Schwarzschild for a = Q = 0,
/// Reissner–Nordström for a = 0, Kerr for Q = 0. Throws InvalidParameter otherwise (negative mass,
/// |a| > M, |Q| > M, NaN, or both a and Q nonzero).
ASRTPHYSICS_EXPORT std::unique_ptr<Spacetime> makeSpacetime(const SpacetimeParameters& p);

/// Solves H(p + μ d) = 0 for μ and returns p + μ d: completes a partly given covariant momentum to
/// a null one. Picks the root with the larger μ if `largerRoot`, the smaller otherwise. Throws
/// InvalidParameter if no real root exists (d cannot make p null here).
ASRTPHYSICS_EXPORT Vec4 completeNullMomentum(const Spacetime& st, const Vec4& x, const Vec4& p,
                                             const Vec4& d, bool largerRoot);
}

#endif
