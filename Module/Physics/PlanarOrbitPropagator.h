// Spherically symmetric holes in the ray's own plane: the spatial orbit as a Newtonian
// central-force problem in the affine parameter, stepped adaptively on four numbers instead of
// eight.
#ifndef asrt_PlanarOrbitPropagator_h
#define asrt_PlanarOrbitPropagator_h

#include "Propagator.h"

#include <array>
#include <cmath>

namespace asrt
{
/// In a metric g = η + f(r) l⊗l (Schwarzschild f = 2M/r, Reissner–Nordström f = 2M/r − Q²/r², both
/// in Kerr–Schild form) a null ray keeps E = −p_t and L = |x × dx/dλ|, and its radius obeys
/// (dr/dλ)² = E² − (1 − f) L²/r². Differentiating, the spatial path x(λ) is exactly Newtonian
/// motion in flat 3-space under the central acceleration
///     d²x/dλ² = ½ L² (f′/r² − 2f/r³) x/r = −L² (3M − 2Q²/r) x / r⁵,
/// the Binet form of u″ + u = 3Mu² − 2Q²u³. Kerr–Schild's spatial coordinates are those of the
/// areal chart, so nothing but t changes chart. The motion stays in the plane of x and dx/dλ; this
/// propagator integrates the four numbers (X, Y, dX/dλ, dY/dλ) of that plane with Dormand and
/// Prince's adaptive explicit pair of order 8 (DOP853) in λ itself (so a segment's Hermite
/// interpolant is exact on straight lines), carries t_KS along with dt/dλ = (E + f n·v)/(1 − f),
/// and rebuilds the Kerr–Schild momentum p = v + f (E + n·p) n, n·p = (n·v + fE)/(1 − f), only at
/// step ends. H = 0 is not built in: |H| measures the drift of (dr/dλ)² + (1 − f)L²/r² from E², the
/// integration's own error.
///
/// Beyond the scene's objects (setFarField) it covers the outgoing tail in one segment to the first
/// sky sphere or the escape sphere, landing on it, and merges incoming far-field steps, so that
/// the object tests are paid only where an object can be hit.
class ASRTPHYSICS_EXPORT PlanarOrbitPropagator final : public Propagator
{
public:
  /// `st` must be Schwarzschild or Reissner–Nordström; throws InvalidParameter otherwise or for
  /// non-positive or non-finite tolerances. Lengths are held to atol·M + rtol·r per step and the
  /// velocity to (atol + rtol)·|v|.
  PlanarOrbitPropagator(const Spacetime& st, double relativeTolerance, double absoluteTolerance);
  void start(const PhasePoint& z) override;
  /// Starts a ray whose first step is to try `firstStep` (affine), as one taking over a ray that
  /// is already far out does: the default start is sized for rays from the camera.
  void start(const PhasePoint& z, double firstStep);
  bool advance(Segment& seg) override;
  PhasePoint state() const override;
  double affineParameter() const override { return this->Lambda; }
  long evaluations() const override { return this->Evaluations; }
  void setLimits(double escapeRadius, double captureRadius) override;
  void setFarField(const FarField* farField) override { this->Far = farField; }

  double energy() const { return this->E; }
  double angularMomentum() const { return std::sqrt(this->L2); }

  /// Largest step, as a fraction of r/|v|: it keeps each segment's cubic Hermite interpolant (the
  /// object tests' curve) as accurate as the integration where the orbit bends most.
  static constexpr double maxStepFraction = 0.25;
  /// Largest integration step, as a fraction of r/|v|; a step is cut into segments of at most
  /// maxStepFraction where an object may be near.
  static constexpr double maxIntegrationFraction = 0.5;
  /// Inside this many M the far field is never used, whatever the scene says: there an outgoing
  /// ray may still turn back (the photon sphere is at ≤ 3M) and rays wind.
  static constexpr double innerFarFieldLimit = 4.0;
  /// Largest angle about the hole one merged far-field segment may sweep: the tracer's per-segment
  /// winding (the angle between the ends) is exact only below π.
  static constexpr double maxMergedSweep = 1.5;
  /// A far-field segment ends this far (relative) beyond the sphere it lands on, so that the
  /// sphere's crossing lies inside the segment, next to its exact end.
  static constexpr double landingMargin = 4e-12;

private:
  /// The plane state: position (X, Y), velocity (U, V) = d/dλ, and Kerr–Schild t.
  struct Plane
  {
    double X = 0, Y = 0, U = 0, V = 0, T = 0;
  };
  /// d/dλ of the state; counts one evaluation.
  Plane slope(const Plane& s);
  using Row = std::array<double, 5>;
  /// DOP853's twelve stages, the new state's slope and the dense output's three extra stages.
  using Stages = std::array<Row, 16>;
  static Row pack(const Plane& p) { return Row{ p.X, p.Y, p.U, p.V, p.T }; }
  static Plane unpack(const Row& r) { return Plane{ r[0], r[1], r[2], r[3], r[4] }; }
  /// One accepted DOP853 step from `s` (its slope `k1`) of at most `h`; returns false if no step
  /// size in 60 attempts met the tolerance. On return `h` is the step taken, `next` the proposal
  /// for the following one, `k13` the slope at the new state (the next step's first stage), and
  /// `stages`, if given, the accepted step's stages.
  bool step(const Plane& s, const Plane& k1, double& h, double& next, Plane& out, Plane& k13,
            Stages* stages = nullptr);

  /// An accepted step that segments are being cut from: DOP853's continuous extension of order 7
  /// (Hairer, Nørsett & Wanner §II.6; dop853.f's contd8) gives the state anywhere inside it, so
  /// that one long integration step can feed several short segments to the object tests.
  struct DenseStep
  {
    bool active = false;
    Plane from, to, toSlope;
    double h = 0, lambda0 = 0;
    double tau = 0;            ///< how far into the step segments have been cut, as a fraction
    bool interpolates = false; ///< F is known
    Stages K;
    std::array<Row, 7> F;
    Plane at(double x) const;
  };
  /// Takes the next step from the current state as a DenseStep.
  bool beginDenseStep();
  /// The dense step's continuous extension (three more evaluations).
  void interpolateDenseStep();
  /// Cuts the next segment from the dense step: at most maxStepFraction·r/|v| long, ending
  /// between the horizon and the capture radius if the ray falls in.
  void cutSegment(Segment& seg);
  /// Covers the outgoing far field up to radius `target` without emitting segments, ending on or
  /// just beyond it.
  bool runOut(double target);
  /// Fills the segment from Start to the current state, which becomes the next Start.
  void finishSegment(Segment& seg, bool farField);
  Vec4 position(const Plane& s) const;
  Vec4 momentum(const Plane& s) const;
  /// A state in the Kerr–Schild chart, as a segment's end needs it.
  /// A state in the Kerr–Schild chart, as a segment's end needs it (t's acceleration left at 0).
  using EndPoint = AffineEnd;
  /// The current state and slope as an EndPoint.
  EndPoint endPoint() const;
  double f(double r) const { return (2.0 * this->M - this->Q2 / r) / r; }
  double radius(const Plane& s) const { return std::sqrt(s.X * s.X + s.Y * s.Y); }
  /// The smallest sky radius beyond r, or the escape radius.
  double nextStopRadius(double r) const;

  double M, Q2, RelTol, AbsTol, HorizonRadius;
  double E = 0, L2 = 0;
  Vec3 E1 = Vec3::UnitX(), E2 = Vec3::UnitY(); // the plane: X along E1, Y along E2
  Plane S, Slope;                              // current state and its slope
  DenseStep Dense;
  EndPoint Start; // where the next segment starts: the last one's end, converted once
  double Lambda = 0;
  double NextStep = 0;
  long Evaluations = 0;
  double EscapeRadius = 1e3, CaptureRadius = 0;
  const FarField* Far = nullptr;
};
}

#endif
