#include "PlanarSeriesPropagator.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace asrt
{
namespace
{
/// Gauss–Legendre's four nodes and weights on [−1, 1]: exact for polynomials of degree 7. On a
/// piece a quarter of r long the integrands r² and r² (E − f L w)/(1 − f) lie far from their
/// poles (where u = 0, at least about four piece lengths away), so the rule's error, which falls
/// as the eighth power of that ratio, stays below the tolerances the presets ask.
constexpr double kNodes[4] = { -0.8611363115940526, -0.3399810435848563, 0.3399810435848563,
                               0.8611363115940526 };
constexpr double kWeights[4] = { 0.3478548451374538, 0.6521451548625461, 0.6521451548625461,
                                 0.3478548451374538 };
/// A series step reaches this fraction of where its last terms meet the tolerance: they estimate
/// the truncation error only as long as the terms fall geometrically.
constexpr double kReachSafety = 0.7;
/// 1/((k + 1)(k + 2)), the recurrence's divisor.
constexpr std::array<double, PlanarSeriesPropagator::Order - 1> recurrenceScale()
{
  std::array<double, PlanarSeriesPropagator::Order - 1> s{};
  for (int k = 0; k + 2 <= PlanarSeriesPropagator::Order; ++k)
    s[k] = 1.0 / ((k + 1.0) * (k + 2.0));
  return s;
}
constexpr std::array<double, PlanarSeriesPropagator::Order - 1> kRecurrenceScale =
  recurrenceScale();
/// Terms below this fraction of the step's tolerance are left out of evaluations.
constexpr double kTermFloor = 1e-3;
/// The affine propagator's first step on the outgoing far field, as a fraction of r/|v|.
constexpr double kFarFirstStep = 0.5;
/// The outgoing far field is run out in closed form when the radial speed at its start is at least
/// this share of E: the periapsis then lies inside 0.6 of the start radius, far enough from the
/// radial integrals' interval for eight nodes.
constexpr double kRunOutRadialShare = 0.8;
/// Gauss–Legendre's eight nodes and weights on [−1, 1].
constexpr double kFarNodes[8] = { -0.9602898564975363, -0.7966664774136267, -0.5255324099163290,
                                  -0.1834346424956498, 0.1834346424956498,  0.5255324099163290,
                                  0.7966664774136267,  0.9602898564975363 };
constexpr double kFarWeights[8] = { 0.1012285362903763, 0.2223810344533745, 0.3137066458778873,
                                    0.3626837833783620, 0.3626837833783620, 0.3137066458778873,
                                    0.2223810344533745, 0.1012285362903763 };
/// No series step sweeps more than this angle.
constexpr double kMaxReach = 2.0;
}

PlanarSeriesPropagator::PlanarSeriesPropagator(const Spacetime& st, double relativeTolerance,
                                               double absoluteTolerance)
  : M(st.mass())
  , Q2(st.charge() * st.charge())
  , RelTol(relativeTolerance)
  , AbsTol(absoluteTolerance)
  , HorizonRadius(st.outerHorizon())
  , Affine(st, relativeTolerance, absoluteTolerance) // checks the spacetime and the tolerances
  // The quintic interpolant's error grows as the sixth power of the segment's length.
  , SegmentFraction(segmentFraction * std::min(1.0, std::pow(relativeTolerance / 1e-10, 1.0 / 6)))
{
}

void PlanarSeriesPropagator::setLimits(double escapeRadius, double captureRadius)
{
  this->EscapeRadius = escapeRadius;
  this->CaptureRadius = captureRadius;
  this->Affine.setLimits(escapeRadius, captureRadius);
}

void PlanarSeriesPropagator::setFarField(const FarField* farField)
{
  this->Far = farField;
  this->Affine.setFarField(farField);
}

double PlanarSeriesPropagator::nextStopRadius(double r) const
{
  return asrt::nextStopRadius(this->Far, r, this->EscapeRadius);
}

// ---------------------------------------------------------------------------------------------
// The plane and the chart

void PlanarSeriesPropagator::start(const PhasePoint& z)
{
  this->E = -z.p[0];
  this->Evaluations = 0;
  this->Delegated = false;
  this->Entered = false;
  this->LambdaOffset = 0.0;
  if (!this->begin(z, 0.0))
  {
    // No angle to step in: the affine-parameter propagator takes the whole ray.
    this->Affine.start(z);
    this->Delegated = true;
  }
}

bool PlanarSeriesPropagator::begin(const PhasePoint& z, double lambda)
{
  const Vec3 x = z.x.tail<3>(), p = z.p.tail<3>();
  const double r = x.norm();
  if (!(r > 0.0))
    return false;
  this->E1 = x / r;
  // dx/dλ = ∂H/∂p = p − f s n with s = l·p = E + n·p (SphericalKerrSchild.h).
  const Vec3 v = p - this->f(1.0 / r) * (this->E + this->E1.dot(p)) * this->E1;
  const Vec3 across = v - v.dot(this->E1) * this->E1;
  this->L = r * across.norm();
  if (!(this->L > radialImpact * this->M * std::abs(this->E)))
    return false;
  this->E2 = across / across.norm();
  this->Start = Point{ 0.0, 1.0 / r, -v.dot(this->E1) / this->L, lambda, z.x[0] };
  this->StartEnd = this->endOf(this->Start);
  this->expand(this->Start);
  return true;
}

PlanarSeriesPropagator::EndPoint PlanarSeriesPropagator::endOf(const Point& q) const
{
  const double c = std::cos(q.phi), s = std::sin(q.phi), u = q.u, w = q.w;
  const double r = 1.0 / u, f = this->f(u);
  EndPoint e;
  const Vec3 x = r * (c * this->E1 + s * this->E2);
  e.x = Vec4(q.t, x.x(), x.y(), x.z());
  // dx/dλ = L u² dx/dφ; its radial part is dr/dλ = −L w. The momentum as PlanarOrbitPropagator
  // rebuilds it: n·p = (n·v + fE)/(1 − f), p = v + f (E + n·p) n, p_t = −E.
  const Vec3 v = this->L * ((-s * u - c * w) * this->E1 + (c * u - s * w) * this->E2);
  const double np = (-this->L * w + f * this->E) / (1.0 - f);
  const Vec3 pp = v + f * (this->E + np) * (c * this->E1 + s * this->E2);
  e.p = Vec4(-this->E, pp.x(), pp.y(), pp.z());
  // Segments are interpolated in λ, as PlanarOrbitPropagator's: far out x(φ) bends as 1/sin,
  // x(λ) is nearly a straight line at constant speed. d²x/dλ² = −L² (3M − 2Q²u) u⁵ x.
  const double dtdl = (this->E + f * (-this->L * w)) / (1.0 - f);
  const Vec3 acc =
    -this->L * this->L * (3.0 * this->M - 2.0 * this->Q2 * u) * u * u * u * u * u * x;
  e.v = Vec4(dtdl, v.x(), v.y(), v.z());
  e.a = Vec4(0.0, acc.x(), acc.y(), acc.z());
  e.lambda = q.lambda;
  return e;
}

PhasePoint PlanarSeriesPropagator::state() const
{
  if (this->Delegated)
    return this->Affine.state();
  return { this->StartEnd.x, this->StartEnd.p };
}

double PlanarSeriesPropagator::affineParameter() const
{
  return this->Delegated ? this->LambdaOffset + this->Affine.affineParameter() : this->Start.lambda;
}

long PlanarSeriesPropagator::evaluations() const
{
  return this->Evaluations + (this->Delegated ? this->Affine.evaluations() : 0);
}

// ---------------------------------------------------------------------------------------------
// The series

double PlanarSeriesPropagator::curvature(double u) const
{
  return (3.0 * this->M - 2.0 * this->Q2 * u) * u * u - u;
}

void PlanarSeriesPropagator::expand(const Point& p)
{
  Series& S = this->Current;
  std::array<double, Order + 1>& a = S.a;
  std::array<double, Order + 1> square{}, cube{};
  a[0] = p.u;
  a[1] = p.w;
  for (int k = 0; k + 2 <= Order; ++k)
  {
    // (u²)_k = Σ a_j a_{k−j}, each pair twice but the middle one.
    double q = 0.0;
    for (int j = 0; 2 * j < k; ++j)
      q += a[j] * a[k - j];
    q *= 2.0;
    if (k % 2 == 0)
      q += a[k / 2] * a[k / 2];
    square[k] = q;
    double rhs = 3.0 * this->M * q - a[k];
    if (this->Q2 != 0.0)
    {
      double c = 0.0;
      for (int j = 0; j <= k; ++j)
        c += square[j] * a[k - j];
      cube[k] = c;
      rhs -= 2.0 * this->Q2 * c;
    }
    a[k + 2] = rhs * kRecurrenceScale[k];
  }
  this->Evaluations += Order;
  // The last two terms bound the truncation of u (against rtol·u + atol·M·u², a length held to
  // rtol·r + atol·M) and of w = du/dφ (against rtol·|(u, w)|, the direction's error).
  const double tolU = this->RelTol * p.u + this->AbsTol * this->M * p.u * p.u;
  const double tolW = this->RelTol * std::sqrt(p.u * p.u + p.w * p.w);
  double reach = kMaxReach;
  const double last = std::max(std::abs(a[Order - 1]), std::abs(a[Order]));
  if (last > 0.0)
  {
    // Both terms at the reach within the tolerance: (tol / |a|)^(1/N) of the larger, a little
    // short for the lower order, whose term falls slower, as the safety factor allows.
    reach = std::min(reach, std::pow(std::min(tolU, tolW / Order) / last, 1.0 / (Order - 1)));
  }
  S.centre = p;
  S.reach = kReachSafety * reach;
  S.tolerance = std::min(tolU, tolW / Order);
}

int PlanarSeriesPropagator::termsWithin(double distance) const
{
  // The terms beyond the last one above round-off at this distance from the centre add nothing.
  // Scanned from the top: the terms fall with k inside the reach.
  const std::array<double, Order + 1>& a = this->Current.a;
  const double floor = kTermFloor * this->Current.tolerance;
  if (!(distance > 0.0))
    return 1;
  // distance^Order by squaring.
  double power = 1.0, square = distance;
  for (int e = Order; e > 0; e >>= 1, square *= square)
    if (e & 1)
      power *= square;
  const double inverse = 1.0 / distance;
  int k = Order;
  for (; k > 1; --k, power *= inverse)
  {
    if (std::abs(a[k]) * power > floor)
      break;
  }
  return k;
}

PlanarSeriesPropagator::Point PlanarSeriesPropagator::at(double phi, int terms) const
{
  const Series& S = this->Current;
  const double s = phi - S.centre.phi;
  double u = S.a[terms], w = terms * S.a[terms];
  for (int k = terms - 1; k >= 1; --k)
  {
    u = u * s + S.a[k];
    w = w * s + k * S.a[k];
  }
  u = u * s + S.a[0];
  return Point{ phi, u, w, S.centre.lambda, S.centre.t };
}

PlanarSeriesPropagator::Point PlanarSeriesPropagator::advanceTo(const Point& from, const Point& to,
                                                                int terms) const
{
  const double phiB = to.phi;
  // λ and t are integrals along the series: Gauss–Legendre over pieces of at most a quarter of r,
  // as long as the segments whose quintic interpolant keeps the integration's accuracy.
  Point p = from;
  double lambda = from.lambda, t = from.t;
  while (p.phi < phiB)
  {
    const double piece = std::min(phiB - p.phi, PlanarOrbitPropagator::maxStepFraction * p.u /
                                                  std::sqrt(p.u * p.u + p.w * p.w));
    const double mid = p.phi + 0.5 * piece, half = 0.5 * piece;
    for (int i = 0; i < 4; ++i)
    {
      // dλ/dφ = 1/(L u²) and dt/dφ = (E − f L w)/((1 − f) L u²): one division for both.
      const Point q = this->at(mid + half * kNodes[i], terms);
      const double f = this->f(q.u);
      const double inverse = half * kWeights[i] / ((1.0 - f) * this->L * q.u * q.u);
      lambda += (1.0 - f) * inverse;
      t += (this->E - f * this->L * q.w) * inverse;
    }
    p = p.phi + piece >= phiB ? to : this->at(p.phi + piece, terms);
  }
  p.lambda = lambda;
  p.t = t;
  return p;
}

template<class G>
double PlanarSeriesPropagator::solve(G g, double lo, double hi) const
{
  // Newton on the series (g returns the value and its φ-derivative), kept inside the bracket
  // [lo, hi] over which g changes sign: bisection where a step would leave it.
  double gLo = g(this->at(lo)).first;
  double x = 0.5 * (lo + hi);
  for (int k = 0; k < 100; ++k)
  {
    const std::pair<double, double> gx = g(this->at(x));
    if (gx.first == 0.0)
      return x;
    if ((gx.first > 0.0) == (gLo > 0.0))
    {
      lo = x;
      gLo = gx.first;
    }
    else
      hi = x;
    double next = x - gx.first / gx.second;
    if (!(next > lo && next < hi))
      next = 0.5 * (lo + hi);
    if (std::abs(next - x) <= 1e-15 * (1.0 + std::abs(x)) || !(hi - lo > 0.0))
      return next;
    x = next;
  }
  return x;
}

// ---------------------------------------------------------------------------------------------
// Segments

void PlanarSeriesPropagator::finishSegment(Segment& seg, const Point& end, bool farField)
{
  const EndPoint b = this->endOf(end);
  setAffineSegment(seg, this->StartEnd, b, farField);
  this->Start = end;
  this->StartEnd = b;
}

void PlanarSeriesPropagator::handOver()
{
  // Beyond the objects the affine steps the tolerance allows are a fair share of r: start there
  // rather than climbing to them from the camera's cautious first step.
  const double speed = this->StartEnd.v.tail<3>().norm();
  this->Affine.start({ this->StartEnd.x, this->StartEnd.p },
                     speed > 0.0 ? kFarFirstStep / (this->Start.u * speed) : 0.0);
  this->LambdaOffset = this->Start.lambda;
}

bool PlanarSeriesPropagator::affineSegment(Segment& seg)
{
  if (!this->Affine.advance(seg))
    return false;
  seg.lambda0 += this->LambdaOffset;
  seg.lambda1 += this->LambdaOffset;
  return true;
}

bool PlanarSeriesPropagator::advance(Segment& seg)
{
  if (this->Delegated)
    return this->affineSegment(seg);
  const double r = 1.0 / this->Start.u;
  const double farRadius = this->Far ? std::max(this->Far->objectRadius,
                                                PlanarOrbitPropagator::innerFarFieldLimit * this->M)
                                     : std::numeric_limits<double>::infinity();
  if (!(r > farRadius) || (this->Start.w > 0.0 && this->Entered))
    return this->nearSegment(seg);
  if (this->Start.w <= 0.0)
  {
    // Going out beyond the objects: in closed form where it converges fast, else the affine
    // propagator takes the rest of the ray.
    if (this->runOut(seg))
      return true;
    this->handOver();
    this->Delegated = true;
    return this->affineSegment(seg);
  }
  this->handOver();
  // Coming in from afar: the affine steps cross the nearly straight path in one segment, up to
  // where the ball of the objects begins; the series take over from its end.
  if (!this->affineSegment(seg))
    return false;
  this->Entered = !seg.farField;
  if (!this->begin(this->Affine.state(), this->LambdaOffset + this->Affine.affineParameter()))
    this->Delegated = true;
  return true;
}

bool PlanarSeriesPropagator::nearSegment(Segment& seg)
{
  const Point from = this->Start;
  const double r = 1.0 / from.u;
  // Segments no longer than segmentFraction·r, or as far as the nearest object where none is
  // near, though no farther than r nor halfway to the sky (PlanarOrbitPropagator's rule).
  double length = this->SegmentFraction * r;
  if (this->Far && this->Far->objectDistance)
  {
    const double clear = 0.9 * this->Far->objectDistance(this->StartEnd.x.tail<3>());
    const double sky = 0.5 * (this->nextStopRadius(r) - r);
    length = std::max(length, std::min({ clear, r, sky }));
  }
  // Arc length per angle, ds/dφ = |(u, w)|/u², falls as u grows (w² + u² = 1/b² + 2Mu³ − Q²u⁴):
  // over a segment on which u is monotonic its larger end value bounds the arc.
  auto arcRate = [](const Point& q) { return std::sqrt(q.u * q.u + q.w * q.w) / (q.u * q.u); };
  double step = length / arcRate(from);
  double seriesEnd = this->Current.centre.phi + this->Current.reach;
  if (from.phi + step > seriesEnd && from.phi > this->Current.centre.phi)
  {
    this->expand(from);
    seriesEnd = from.phi + this->Current.reach;
  }
  // No sliver is left before the series' end.
  double end = from.phi + step > seriesEnd - 0.25 * step ? seriesEnd : from.phi + step;
  const int terms = this->termsWithin(end - this->Current.centre.phi);
  Point q = this->at(end, terms);
  if ((end - from.phi) * arcRate(q) > length)
  {
    end = from.phi + length / arcRate(q);
    q = this->at(end, terms);
  }
  if (!(q.u > 0.0) || !std::isfinite(q.u))
    return false;
  // As PlanarOrbitPropagator's: a segment that would end inside the horizon ends between it and
  // the capture radius instead, where the tracer reports the capture.
  if (this->CaptureRadius > this->HorizonRadius && 1.0 / q.u < this->HorizonRadius)
  {
    const double target = 2.0 / (this->HorizonRadius + this->CaptureRadius);
    end = this->solve([target](const Point& p) { return std::make_pair(p.u - target, p.w); },
                      from.phi, end);
    q = this->at(end);
  }
  finishSegment(seg, this->advanceTo(from, q, terms), false);
  return true;
}

bool PlanarSeriesPropagator::runOut(Segment& seg)
{
  // The outgoing far field in one segment, landing just beyond the next sky sphere (or the escape
  // sphere): its end angle from the series, λ and t from the radial integrals
  //   λ = ∫ dr/ṙ,  t = ∫ (E/((1 − f) ṙ) + f/(1 − f)) dr,  ṙ² = E² − (1 − f) L²/r²,
  // whose integrands tend to constants plus a 1/r term far out. Less those, and in s = 1/r, what is
  // left is smooth from the start to s = 0 when the periapsis (ṙ = 0) lies well inside the start:
  // Gauss–Legendre's eight nodes then reach round-off.
  const Point from = this->Start;
  const double r0 = 1.0 / from.u;
  const double E2 = this->E * this->E;
  auto rdot2 = [&](double s) { return E2 - (1.0 - this->f(s)) * this->L * this->L * s * s; };
  if (!(rdot2(from.u) >= kRunOutRadialShare * kRunOutRadialShare * E2))
    return false;
  const double goal = this->nextStopRadius(r0) * (1.0 + PlanarOrbitPropagator::landingMargin),
               uGoal = 1.0 / goal;
  const double limit = from.phi + PlanarOrbitPropagator::maxMergedSweep;
  // The angle where u falls to 1/goal, series after series.
  double end = std::numeric_limits<double>::quiet_NaN();
  Point p = from;
  for (int series = 0; series < 64 && std::isnan(end); ++series)
  {
    if (p.phi > this->Current.centre.phi)
      this->expand(p);
    const double stop = std::min(this->Current.centre.phi + this->Current.reach, limit);
    const Point q = this->at(stop);
    if (q.u <= uGoal)
      end = this->solve([uGoal](const Point& z) { return std::make_pair(z.u - uGoal, z.w); }, p.phi,
                        stop);
    else if (stop == limit || !(q.w < 0.0))
      return false; // sweeps too far round for one segment, or turns
    p = q;
  }
  if (std::isnan(end))
    return false;
  Point q = this->at(end);
  // Far out 1/ṙ → 1/|E|, and dt/dr → σ + 2M (σ + 1)/r with σ the sign of E (rays traced back in
  // time have E < 0).
  const double E = std::abs(this->E), sigma = this->E < 0.0 ? -1.0 : 1.0;
  const double logTerm = 2.0 * this->M * (sigma + 1.0);
  double lambda = (goal - r0) / E, t = sigma * (goal - r0) + logTerm * std::log(goal / r0);
  const double mid = 0.5 * (from.u + uGoal), half = 0.5 * (from.u - uGoal);
  for (int i = 0; i < 8; ++i)
  {
    const double s = mid + half * kFarNodes[i], f = this->f(s);
    const double rdot = std::sqrt(rdot2(s)), weight = half * kFarWeights[i] / (s * s);
    lambda += weight * (1.0 / rdot - 1.0 / E);
    t += weight * (this->E / ((1.0 - f) * rdot) + f / (1.0 - f) - sigma - logTerm * s);
  }
  q.lambda = from.lambda + lambda;
  q.t = from.t + t;
  this->finishSegment(seg, q, true);
  return true;
}
}
