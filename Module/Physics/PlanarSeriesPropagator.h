// Spherically symmetric holes in the ray's own plane, stepped in the orbit's angle: the Binet
// equation u″ + u = 3Mu² − 2Q²u³ (u = 1/r) has a polynomial right-hand side, so its Taylor series
// about any point follows from two coefficients by a recurrence, and a handful of series cover a
// ray from the camera through the strong field.
#ifndef asrt_PlanarSeriesPropagator_h
#define asrt_PlanarSeriesPropagator_h

#include "PlanarOrbitPropagator.h"

#include <array>

namespace asrt
{
/// The same orbit as PlanarOrbitPropagator (see there: Kerr–Schild's spatial coordinates are the
/// areal chart's, the path lies in the plane of x and dx/dλ), parameterised by its angle φ in that
/// plane instead of λ. With u = 1/r and w = du/dφ,
///     u(φ₀ + s) = Σ a_k s^k,  a_{k+2} = (3M (u²)_k − 2Q² (u³)_k − a_k) / ((k + 1)(k + 2)),
/// the Cauchy products (u²)_k, (u³)_k needing only a_0 … a_k. A series step ends where its last
/// two terms reach the tolerance, typically a radian or so of the orbit: u(φ) is meromorphic, its
/// nearest complex pole (r = 0) about π away at the photon sphere and farther outside it.
///
/// Segments are cut from the series in φ with the same length rule as PlanarOrbitPropagator and
/// interpolated as its are, in λ (quintic Hermite from dx/dλ and d²x/dλ²); λ and t, which the
/// series do not carry, come from Gauss–Legendre quadrature of dλ/dφ = 1/(L u²) and
/// dt/dφ = (E − f L w) / ((1 − f) L u²) over pieces no longer than a quarter of r.
///
/// Three parts of a ray are handed to PlanarOrbitPropagator, restarted from the exact state there:
/// a ray that is nearly radial (no angle to step in), and the far field beyond the scene's
/// objects, coming in and going out, where u → 0 and dλ/dφ grows without bound while the path is
/// nearly straight: the adaptive affine steps cross it in one segment, landing on the sky.
class ASRTPHYSICS_EXPORT PlanarSeriesPropagator final : public Propagator
{
public:
  /// As PlanarOrbitPropagator's: `st` Schwarzschild or Reissner–Nordström, tolerances positive
  /// and finite (InvalidParameter otherwise). u is held to rtol·u + atol·M·u² per series step,
  /// which is a length held to rtol·r + atol·M.
  PlanarSeriesPropagator(const Spacetime& st, double relativeTolerance, double absoluteTolerance);
  void start(const PhasePoint& z) override;
  bool advance(Segment& seg) override;
  PhasePoint state() const override;
  double affineParameter() const override;
  long evaluations() const override;
  void setLimits(double escapeRadius, double captureRadius) override;
  void setFarField(const FarField* farField) override;

  /// Terms of each series: its truncation error falls as (s/ρ)^Order for ρ the distance to the
  /// nearest pole, so the order sets how far a step reaches at a tolerance.
  static constexpr int Order = 24;
  /// Rays of impact parameter below this (in M) are stepped in λ: in φ they barely move.
  static constexpr double radialImpact = 1e-3;
  /// Largest segment where an object may be near, as a fraction of r, at rtol 1e-10 and above
  /// (shorter as rtol^(1/6) below, the quintic interpolant's order). PlanarOrbitPropagator's
  /// segments of up to a quarter of r mostly end early, at its steps' ends; these run their full
  /// length, and at a quarter of r the affine parameter of Fig. 1's hit points, read off the
  /// interpolant, strayed from the reference's by 10⁻⁸ relative.
  static constexpr double segmentFraction = 0.15;

private:
  /// A point of the orbit: the angle, u = 1/r, w = du/dφ, λ and t.
  struct Point
  {
    double phi = 0, u = 0, w = 0, lambda = 0, t = 0;
  };
  /// The series of u about Centre.phi, valid for φ − Centre.phi in [0, Reach].
  struct Series
  {
    Point centre;
    double reach = 0;
    double tolerance = 0; ///< of u at the reach
    std::array<double, Order + 1> a{};
  };
  /// Sets up the plane and the series from a state at affine parameter `lambda`; false for a ray
  /// too nearly radial to step in φ.
  bool begin(const PhasePoint& z, double lambda);
  /// Builds the series about `p` and chooses its reach.
  void expand(const Point& p);
  /// u and w at angle φ (within the series' reach) from its first `terms` terms, λ and t left at
  /// the centre's.
  Point at(double phi, int terms = Order) const;
  /// The terms that matter up to `distance` from the centre.
  int termsWithin(double distance) const;
  /// u″ from the Binet equation.
  double curvature(double u) const;
  /// `to` (u and w known, on the current series) with λ and t integrated from `from`, evaluating
  /// the series to `terms` (termsWithin the farther end's distance from the centre).
  Point advanceTo(const Point& from, const Point& to, int terms) const;
  /// The angle in [lo, hi] where g(at(φ)) = 0, g changing sign over it.
  template<class G>
  double solve(G g, double lo, double hi) const;
  /// The next segment where an object may be hit.
  bool nearSegment(Segment& seg);
  /// Fills `seg` from Start to `end` (which becomes Start).
  void finishSegment(Segment& seg, const Point& end, bool farField);
  /// The outgoing far field in one segment from Start, in closed form; false where that does not
  /// converge fast (a periapsis just inside the start, or a sweep beyond maxMergedSweep).
  bool runOut(Segment& seg);
  /// Starts the affine-parameter propagator from Start.
  void handOver();
  /// Its next segment, on this ray's λ.
  bool affineSegment(Segment& seg);

  /// What a segment's end needs in the Kerr–Schild chart (t's acceleration left at 0).
  using EndPoint = AffineEnd;
  EndPoint endOf(const Point& q) const;
  double dlambda(double u) const { return 1.0 / (this->L * u * u); }
  /// dt/dφ = (dt/dλ)(dλ/dφ), dt/dλ = (E + f n·v)/(1 − f) and n·v = dr/dλ = −L w.
  double dtime(double u, double w) const
  {
    const double f = this->f(u);
    return (this->E - f * this->L * w) / ((1.0 - f) * this->L * u * u);
  }
  double f(double u) const { return (2.0 * this->M - this->Q2 * u) * u; }
  double nextStopRadius(double r) const;

  double M, Q2, RelTol, AbsTol, HorizonRadius;
  double E = 0, L = 0;
  Vec3 E1 = Vec3::UnitX(), E2 = Vec3::UnitY(); // φ = 0 along E1, increasing towards E2
  Point Start;                                 // the end of the last segment
  EndPoint StartEnd;                           // Start in the chart
  bool Entered = false;                        // inside the far field's ball once
  Series Current;
  long Evaluations = 0;
  double EscapeRadius = 1e3, CaptureRadius = 0;
  const FarField* Far = nullptr;
  /// Nearly radial rays and the outgoing far field: λ continues from LambdaOffset.
  PlanarOrbitPropagator Affine;
  double SegmentFraction;
  bool Delegated = false;
  double LambdaOffset = 0;
};
}

#endif
