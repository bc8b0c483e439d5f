#include "PlanarOrbitPropagator.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>

namespace asrt
{
PlanarOrbitPropagator::PlanarOrbitPropagator(const Spacetime& st, double relativeTolerance,
                                             double absoluteTolerance)
  : M(st.mass())
  , Q2(st.charge() * st.charge())
  , RelTol(relativeTolerance)
  , AbsTol(absoluteTolerance)
  , HorizonRadius(st.outerHorizon())
{
  if (st.kind() != SpacetimeKind::Schwarzschild && st.kind() != SpacetimeKind::ReissnerNordstrom)
  {
    throw InvalidParameter("the planar orbit method models spherically symmetric holes "
                           "(Schwarzschild, Reissner-Nordstrom) only, not " +
                           st.name());
  }
  if (!(relativeTolerance > 0.0) || !(absoluteTolerance > 0.0) ||
      !std::isfinite(relativeTolerance) || !std::isfinite(absoluteTolerance))
  {
    std::ostringstream os;
    os << "planar orbit tolerances must be positive and finite, got rtol=" << relativeTolerance
       << ", atol=" << absoluteTolerance;
    throw InvalidParameter(os.str());
  }
}

void PlanarOrbitPropagator::setLimits(double escapeRadius, double captureRadius)
{
  this->EscapeRadius = escapeRadius;
  this->CaptureRadius = captureRadius;
}

// ---------------------------------------------------------------------------------------------
// The plane and the chart

void PlanarOrbitPropagator::start(const PhasePoint& z)
{
  const Vec3 x = z.x.tail<3>(), p = z.p.tail<3>();
  this->E = -z.p[0];
  const double r = x.norm();
  this->E1 = r > 0.0 ? Vec3(x / r) : Vec3::UnitX();
  // dx/dλ = ∂H/∂p = p − f s n with s = l·p = E + n·p (SphericalKerrSchild.h).
  const double f = r > 0.0 ? this->f(r) : 0.0;
  const Vec3 v = p - f * (this->E + this->E1.dot(p)) * this->E1;
  const Vec3 across = v - v.dot(this->E1) * this->E1;
  if (across.norm() > 1e-15 * v.norm())
    this->E2 = across.normalized();
  else
  {
    // A radial ray: L = 0, no force, a straight line in any plane through it.
    const Vec3 trial = std::abs(this->E1.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
    this->E2 = (trial - trial.dot(this->E1) * this->E1).normalized();
  }
  this->S = Plane{ r, 0.0, v.dot(this->E1), v.dot(this->E2), z.x[0] };
  this->L2 = r * r * this->S.V * this->S.V;
  this->Lambda = 0.0;
  this->Evaluations = 0;
  this->Dense.active = false;
  this->Slope = this->slope(this->S);
  this->Start = this->endPoint();
  // The local error grows as h⁹: start near the step the tolerance allows, so that the controller
  // does not spend segments climbing to it.
  const double speed = std::hypot(this->S.U, this->S.V);
  this->NextStep = (speed > 0.0 ? r / speed : 1.0) *
                   std::min(maxStepFraction, 0.5 * std::pow(this->RelTol, 1.0 / 8));
}

void PlanarOrbitPropagator::start(const PhasePoint& z, double firstStep)
{
  this->start(z);
  if (firstStep > 0.0 && std::isfinite(firstStep))
    this->NextStep = firstStep;
}

PlanarOrbitPropagator::Plane PlanarOrbitPropagator::slope(const Plane& s)
{
  ++this->Evaluations;
  const double inv = 1.0 / std::sqrt(s.X * s.X + s.Y * s.Y);
  const double f = (2.0 * this->M - this->Q2 * inv) * inv;
  const double inv2 = inv * inv;
  const double k = this->L2 * (3.0 * this->M - 2.0 * this->Q2 * inv) * inv2 * inv2 * inv;
  const double nv = (s.X * s.U + s.Y * s.V) * inv;
  return Plane{ s.U, s.V, -k * s.X, -k * s.Y, (this->E + f * nv) / (1.0 - f) };
}

Vec4 PlanarOrbitPropagator::position(const Plane& s) const
{
  const Vec3 x = s.X * this->E1 + s.Y * this->E2;
  return Vec4(s.T, x.x(), x.y(), x.z());
}

Vec4 PlanarOrbitPropagator::momentum(const Plane& s) const
{
  // The inverse of start()'s dx/dλ: n·p = (n·v + fE)/(1 − f), p = v + f (E + n·p) n, p_t = −E.
  const double r = this->radius(s);
  const double f = this->f(r);
  const double nv = (s.X * s.U + s.Y * s.V) / r;
  const double np = (nv + f * this->E) / (1.0 - f);
  const double c = f * (this->E + np) / r;
  const Vec3 p = (s.U + c * s.X) * this->E1 + (s.V + c * s.Y) * this->E2;
  return Vec4(-this->E, p.x(), p.y(), p.z());
}

PlanarOrbitPropagator::EndPoint PlanarOrbitPropagator::endPoint() const
{
  // The slope holds dx/dλ in its X, Y and d²x/dλ² = −k(r) x in its U, V: nothing to recompute.
  const Vec3 v = this->Slope.X * this->E1 + this->Slope.Y * this->E2;
  const Vec3 a = this->Slope.U * this->E1 + this->Slope.V * this->E2;
  return { this->position(this->S), this->momentum(this->S),
           Vec4(this->Slope.T, v.x(), v.y(), v.z()), Vec4(0.0, a.x(), a.y(), a.z()), this->Lambda };
}

PhasePoint PlanarOrbitPropagator::state() const
{
  return { this->position(this->S), this->momentum(this->S) };
}

double PlanarOrbitPropagator::nextStopRadius(double r) const
{
  return asrt::nextStopRadius(this->Far, r, this->EscapeRadius);
}

// ---------------------------------------------------------------------------------------------
// Stepping

namespace
{
// Dormand & Prince's DOP853 tableau (Hairer, Nørsett & Wanner, Solving ODEs I, 2nd ed., §II.10,
// and their dop853.f): stage rows 1-11, the order-8 weights (row 12), and the order-5 and order-3
// error weights over the 12 stages.
constexpr double A[13][12] = {
  { 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0 },
  { 5.26001519587677318785587544488e-2, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0 },
  { 1.97250569845378994544595329183e-2, 5.91751709536136983633785987549e-2, 0, 0, 0, 0, 0, 0, 0, 0,
    0, 0 },
  { 2.95875854768068491816892993775e-2, 0, 8.87627564304205475450678981324e-2, 0, 0, 0, 0, 0, 0, 0,
    0, 0 },
  { 2.41365134159266685502369798665e-1, 0, -8.84549479328286085344864962717e-1,
    9.24834003261792003115737966543e-1, 0, 0, 0, 0, 0, 0, 0, 0 },
  { 3.7037037037037037037037037037e-2, 0, 0, 1.70828608729473871279604482173e-1,
    1.25467687566822425016691814123e-1, 0, 0, 0, 0, 0, 0, 0 },
  { 3.7109375e-2, 0, 0, 1.70252211019544039314978060272e-1, 6.02165389804559606850219397283e-2,
    -1.7578125e-2, 0, 0, 0, 0, 0, 0 },
  { 3.70920001185047927108779319836e-2, 0, 0, 1.70383925712239993810214054705e-1,
    1.07262030446373284651809199168e-1, -1.53194377486244017527936158236e-2,
    8.27378916381402288758473766002e-3, 0, 0, 0, 0, 0 },
  { 6.24110958716075717114429577812e-1, 0, 0, -3.36089262944694129406857109825,
    -8.68219346841726006818189891453e-1, 2.75920996994467083049415600797e1,
    2.01540675504778934086186788979e1, -4.34898841810699588477366255144e1, 0, 0, 0, 0 },
  { 4.77662536438264365890433908527e-1, 0, 0, -2.48811461997166764192642586468,
    -5.90290826836842996371446475743e-1, 2.12300514481811942347288949897e1,
    1.52792336328824235832596922938e1, -3.32882109689848629194453265587e1,
    -2.03312017085086261358222928593e-2, 0, 0, 0 },
  { -9.3714243008598732571704021658e-1, 0, 0, 5.18637242884406370830023853209,
    1.09143734899672957818500254654, -8.14978701074692612513997267357,
    -1.85200656599969598641566180701e1, 2.27394870993505042818970056734e1,
    2.49360555267965238987089396762, -3.0467644718982195003823669022, 0, 0 },
  { 2.27331014751653820792359768449, 0, 0, -1.05344954667372501984066689879e1,
    -2.00087205822486249909675718444, -1.79589318631187989172765950534e1,
    2.79488845294199600508499808837e1, -2.85899827713502369474065508674,
    -8.87285693353062954433549289258, 1.23605671757943030647266201528e1,
    6.43392746015763530355970484046e-1, 0 },
  { 5.42937341165687622380535766363e-2, 0, 0, 0, 0, 4.45031289275240888144113950566,
    1.89151789931450038304281599044, -5.8012039600105847814672114227,
    3.1116436695781989440891606237e-1, -1.52160949662516078556178806805e-1,
    2.01365400804030348374776537501e-1, 4.47106157277725905176885569043e-2 },
};
constexpr double E5[12] = { 0.1312004499419488073250102996e-1,
                            0,
                            0,
                            0,
                            0,
                            -0.1225156446376204440720569753e1,
                            -0.4957589496572501915214079952,
                            0.1664377182454986536961530415e1,
                            -0.3503288487499736816886487290,
                            0.3341791187130174790297318841,
                            0.8192320648511571246570742613e-1,
                            -0.2235530786388629525884427845e-1 };
constexpr double E3[12] = { 5.42937341165687622380535766363e-2 - 0.244094488188976377952755905512,
                            0,
                            0,
                            0,
                            0,
                            4.45031289275240888144113950566,
                            1.89151789931450038304281599044,
                            -5.8012039600105847814672114227,
                            3.1116436695781989440891606237e-1 - 0.733846688281611857341361741547,
                            -1.52160949662516078556178806805e-1,
                            2.01365400804030348374776537501e-1,
                            4.47106157277725905176885569043e-2 -
                              0.220588235294117647058823529412e-1 };
// The dense output's three extra stages (rows 13-15, over the 12 stages, the new state's slope
// and the extra stages before them) and its coefficients D (dop853.f's contd8).
constexpr double AExtra[3][15] = {
  { 5.61675022830479523392909219681e-2, 0, 0, 0, 0, 0, 2.53500210216624811088794765333e-1,
    -2.46239037470802489917441475441e-1, -1.24191423263816360469010140626e-1,
    1.5329179827876569731206322685e-1, 8.20105229563468988491666602057e-3,
    7.56789766054569976138603589584e-3, -8.298e-3, 0, 0 },
  { 3.18346481635021405060768473261e-2, 0, 0, 0, 0, 2.83009096723667755288322961402e-2,
    5.35419883074385676223797384372e-2, -5.49237485713909884646569340306e-2, 0, 0,
    -1.08347328697249322858509316994e-4, 3.82571090835658412954920192323e-4,
    -3.40465008687404560802977114492e-4, 1.41312443674632500278074618366e-1, 0 },
  { -4.28896301583791923408573538692e-1, 0, 0, 0, 0, -4.69762141536116384314449447206,
    7.68342119606259904184240953878, 4.06898981839711007970213554331,
    3.56727187455281109270669543021e-1, 0, 0, 0, -1.39902416515901462129418009734e-3,
    2.9475147891527723389556272149, -9.15095847217987001081870187138 },
};
constexpr double DenseWeights[4][16] = {
  { -0.84289382761090128651353491142e1, 0, 0, 0, 0, 0.56671495351937776962531783590,
    -0.30689499459498916912797304727e1, 0.23846676565120698287728149680e1,
    0.21170345824450282767155149946e1, -0.87139158377797299206789907490,
    0.22404374302607882758541771650e1, 0.63157877876946881815570249290,
    -0.88990336451333310820698117400e-1, 0.18148505520854727256656404962e2,
    -0.91946323924783554000451984436e1, -0.44360363875948939664310572000e1 },
  { 0.10427508642579134603413151009e2, 0, 0, 0, 0, 0.24228349177525818288430175319e3,
    0.16520045171727028198505394887e3, -0.37454675472269020279518312152e3,
    -0.22113666853125306036270938578e2, 0.77334326684722638389603898808e1,
    -0.30674084731089398182061213626e2, -0.93321305264302278729567221706e1,
    0.15697238121770843886131091075e2, -0.31139403219565177677282850411e2,
    -0.93529243588444783865713862664e1, 0.35816841486394083752465898540e2 },
  { 0.19985053242002433820987653617e2, 0, 0, 0, 0, -0.38703730874935176555105901742e3,
    -0.18917813819516756882830838328e3, 0.52780815920542364900561016686e3,
    -0.11573902539959630126141871134e2, 0.68812326946963000169666922661e1,
    -0.10006050966910838403183860980e1, 0.77771377980534432092869265740,
    -0.27782057523535084065932004339e1, -0.60196695231264120758267380846e2,
    0.84320405506677161018159903784e2, 0.11992291136182789328035130030e2 },
  { -0.25693933462703749003312586129e2, 0, 0, 0, 0, -0.15418974869023643374053993627e3,
    -0.23152937917604549567536039109e3, 0.35763911791061412378285349910e3,
    0.93405324183624310003907691704e2, -0.37458323136451633156875139351e2,
    0.10409964950896230045147246184e3, 0.29840293426660503123344363579e2,
    -0.43533456590011143754432175058e2, 0.96324553959188282948394950600e2,
    -0.39177261675615439165231486172e2, -0.14972683625798562581422125276e3 },
};

}

bool PlanarOrbitPropagator::step(const Plane& s, const Plane& k1, double& h, double& next,
                                 Plane& out, Plane& k13, Stages* stages)
{
  // An explicit embedded pair of order 8 (error estimated at orders 5 and 3): far fewer segments
  // than Dormand–Prince 5(4) at the tolerances a hit point needs, on a right-hand side that costs
  // one square root and two divisions.
  const Row y = pack(s);
  Stages local;
  Stages& K = stages ? *stages : local;
  K[0] = pack(k1);
  for (int attempt = 0; attempt < 60; ++attempt)
  {
    // Fully unrolled, the tableau's zeros drop out at compile time.
#pragma GCC unroll 12
    for (int i = 1; i < 12; ++i)
    {
      Row z = y;
#pragma GCC unroll 12
      for (int j = 0; j < i; ++j)
      {
        if (A[i][j] != 0.0)
          for (int c = 0; c < 5; ++c)
            z[c] += h * A[i][j] * K[j][c];
      }
      K[i] = pack(this->slope(unpack(z)));
    }
    Row z = y, e5{}, e3{};
#pragma GCC unroll 12
    for (int j = 0; j < 12; ++j)
      for (int c = 0; c < 5; ++c)
      {
        z[c] += h * A[12][j] * K[j][c];
        e5[c] += E5[j] * K[j][c];
        e3[c] += E3[j] * K[j][c];
      }
    out = unpack(z);
    // Lengths against atol·M + rtol·r, velocities relative to the speed: the error that moves a hit
    // point, and the direction error that the sky sees magnified by its radius. t is carried, not
    // controlled. The combination of the two estimates is Hairer's (dop853.f).
    const double r = std::max(this->radius(s), this->radius(out));
    const double speed2 = std::max(s.U * s.U + s.V * s.V, out.U * out.U + out.V * out.V);
    const double scaleX = this->AbsTol * this->M + this->RelTol * r;
    const double scaleV2 = (this->AbsTol + this->RelTol) * (this->AbsTol + this->RelTol) * speed2;
    auto norm2 = [&](const Row& e)
    {
      return std::max((e[0] * e[0] + e[1] * e[1]) / (scaleX * scaleX),
                      (e[2] * e[2] + e[3] * e[3]) / scaleV2);
    };
    const double n5 = norm2(e5), n3 = norm2(e3);
    const double denominator = n5 + 0.01 * n3;
    const double norm = denominator > 0.0 ? std::abs(h) * n5 / std::sqrt(denominator) : 0.0;
    if (!std::isfinite(norm) || !std::isfinite(out.T) || !std::isfinite(out.X))
    {
      h *= 0.25;
      continue;
    }
    // 0.9 norm^(−1/8), by three square roots: pow costs several times as much.
    const double factor =
      std::clamp(0.9 / std::sqrt(std::sqrt(std::sqrt(std::max(norm, 1e-16)))), 0.2, 6.0);
    if (norm <= 1.0)
    {
      k13 = this->slope(out);
      // The controller's proposal assumes that the next step meets this one's error constant,
      // but the constant follows the orbit's scale: the force goes as r⁻⁴, and the step the
      // tolerance allows about as r. Coming in, the proposal is scaled by the radius ratio, which
      // keeps the next radius from rejecting it (a quarter of all attempts on Fig. 1 without).
      // Going out it is not lengthened beyond the controller's: an embedded estimate over a step
      // that spans scales of r is not to be trusted.
      next = h * factor * std::min(1.0, this->radius(out) / this->radius(s));
      return true;
    }
    h *= std::max(factor, 0.1);
  }
  return false;
}

bool PlanarOrbitPropagator::runOut(double target)
{
  const double goal = target * (1.0 + landingMargin);
  const double x0 = this->S.X, y0 = this->S.Y;
  for (int k = 0; k < 10000; ++k)
  {
    const double r = this->radius(this->S);
    const double xv = this->S.X * this->S.U + this->S.Y * this->S.V;
    // Stop where a segment must: on the sphere, if the ray turns inwards, or before the segment
    // sweeps too far round.
    if (r >= target || xv <= 0.0 ||
        std::atan2(std::abs(x0 * this->S.Y - y0 * this->S.X), x0 * this->S.X + y0 * this->S.Y) >
          maxMergedSweep)
      return true;
    // The straight line's distance to the goal: the orbit bends inwards, so it falls a little short
    // of it, and the next (much shorter) prediction closes most of the rest.
    const double vv = this->S.U * this->S.U + this->S.V * this->S.V;
    const double dl = (-xv + std::sqrt(xv * xv + vv * (goal * goal - r * r))) / vv;
    double h = std::min(this->NextStep, dl), next;
    Plane out, k13;
    if (!this->step(this->S, this->Slope, h, next, out, k13))
      return false;
    this->S = out;
    this->Slope = k13;
    this->Lambda += h;
    this->NextStep = std::max(next, h); // a landing step is short by choice, not by the tolerance
  }
  return true;
}

void PlanarOrbitPropagator::finishSegment(Segment& seg, bool farField)
{
  // The segment runs from the end point kept since the last one to the current state, with t's
  // second derivative left out (the scene does not look at t, and its ends and slopes stay exact).
  const EndPoint b = this->endPoint();
  setAffineSegment(seg, this->Start, b, farField);
  this->Start = b;
}

bool PlanarOrbitPropagator::advance(Segment& seg)
{
  if (this->Dense.active && this->Dense.tau < 1.0)
  {
    this->cutSegment(seg);
    return true;
  }
  this->Dense.active = false;
  const Plane from = this->S;
  const double r = this->radius(from);
  const double farRadius = this->Far
                             ? std::max(this->Far->objectRadius, innerFarFieldLimit * this->M)
                             : std::numeric_limits<double>::infinity();
  const bool outgoing = from.X * from.U + from.Y * from.V > 0.0;
  if (r > farRadius && outgoing)
  {
    if (!this->runOut(this->nextStopRadius(r)))
      return false;
    this->finishSegment(seg, true);
    return true;
  }
  // Coming in through the far field, steps merge into one segment while they stay outside it, keep
  // coming in and sweep little. The step that leaves it stays the dense step, to be cut into
  // segments: after the merged segment if there is one, at once if not.
  int merged = 0;
  for (;;)
  {
    if (!this->beginDenseStep())
      return false;
    if (!(r > farRadius))
      break;
    const Plane& out = this->Dense.to;
    const bool stillFar = this->radius(out) > farRadius && out.X * out.U + out.Y * out.V < 0.0 &&
                          std::atan2(std::abs(from.X * out.Y - from.Y * out.X),
                                     from.X * out.X + from.Y * out.Y) <= maxMergedSweep;
    if (!stillFar)
    {
      if (merged == 0)
        break;
      this->finishSegment(seg, true);
      return true;
    }
    this->S = out;
    this->Slope = this->Dense.toSlope;
    this->Lambda += this->Dense.h;
    this->Dense.active = false;
    ++merged;
  }
  this->cutSegment(seg);
  return true;
}

bool PlanarOrbitPropagator::beginDenseStep()
{
  // An embedded error estimate cannot be trusted over a step that spans scales of r (from far away
  // into the strong field in one go): steps stay below maxIntegrationFraction·r/|v|.
  DenseStep& d = this->Dense;
  const double speed = std::sqrt(this->S.U * this->S.U + this->S.V * this->S.V);
  double h = std::min(this->NextStep, maxIntegrationFraction * this->radius(this->S) / speed), next;
  Plane out, k13;
  if (!this->step(this->S, this->Slope, h, next, out, k13, &d.K))
    return false;
  this->NextStep = next;
  d.K[12] = pack(k13);
  d.from = this->S;
  d.to = out;
  d.toSlope = k13;
  d.h = h;
  d.lambda0 = this->Lambda;
  d.tau = 0.0;
  d.active = true;
  d.interpolates = false;
  return true;
}

void PlanarOrbitPropagator::interpolateDenseStep()
{
  // Only a step cut into several segments needs its inside: the three extra stages are paid then.
  DenseStep& d = this->Dense;
  const double h = d.h;
  const Row y0 = pack(d.from), y1 = pack(d.to);
  for (int s = 13; s < 16; ++s)
  {
    Row z = y0;
    for (int j = 0; j < s; ++j)
    {
      const double a = h * AExtra[s - 13][j];
      if (a != 0.0)
        for (int c = 0; c < 5; ++c)
          z[c] += a * d.K[j][c];
    }
    d.K[s] = pack(this->slope(unpack(z)));
  }
  for (int c = 0; c < 5; ++c)
  {
    const double delta = y1[c] - y0[c];
    d.F[0][c] = delta;
    d.F[1][c] = h * d.K[0][c] - delta;
    d.F[2][c] = 2.0 * delta - h * (d.K[12][c] + d.K[0][c]);
    for (int i = 0; i < 4; ++i)
    {
      double sum = 0.0;
      for (int j = 0; j < 16; ++j)
        sum += DenseWeights[i][j] * d.K[j][c];
      d.F[3 + i][c] = h * sum;
    }
  }
  d.interpolates = true;
}

PlanarOrbitPropagator::Plane PlanarOrbitPropagator::DenseStep::at(double x) const
{
  // Horner-like evaluation of dop853.f's contd8: y0 + x(F0 + (1−x)(F1 + x(F2 + (1−x)(F3 + ...)))).
  Row y{};
  for (int i = 0; i < 7; ++i)
  {
    const double w = i % 2 == 0 ? x : 1.0 - x;
    for (int c = 0; c < 5; ++c)
      y[c] = (y[c] + this->F[6 - i][c]) * w;
  }
  const Row y0 = pack(this->from);
  for (int c = 0; c < 5; ++c)
    y[c] += y0[c];
  return unpack(y);
}

void PlanarOrbitPropagator::cutSegment(Segment& seg)
{
  DenseStep& d = this->Dense;
  const Plane from = this->S;
  const double r = this->radius(from);
  const double speed = std::sqrt(from.U * from.U + from.V * from.V);
  // Segments no longer than maxStepFraction·r, so that their interpolant is as good as the
  // integration where an object may be hit. Where none can be, a segment may run as far as the
  // nearest object (a path of arc length ≤ d stays in the ball of radius d about its start, which
  // holds no object), though no farther than r (it must sweep less than π about the hole for the
  // winding) nor halfway to the sky (whose crossing needs the accurate interpolant).
  double length = maxStepFraction * r;
  if (this->Far && this->Far->objectDistance)
  {
    const double clear = 0.9 * this->Far->objectDistance(this->Start.x.tail<3>());
    const double sky = 0.5 * (this->nextStopRadius(r) - r);
    length = std::max(length, std::min({ clear, r, sky }));
  }
  // Arc length ≈ |v| Δλ; no sliver is left at the step's end.
  const double most = length / speed / d.h;
  double tau = d.tau + most;
  if (tau > 1.0 - 0.25 * most)
    tau = 1.0;
  if (tau < 1.0 && !d.interpolates)
    this->interpolateDenseStep();
  Plane end = tau == 1.0 ? d.to : d.at(tau);
  // λ is the affine parameter, so a segment may run from outside the capture sphere to inside the
  // horizon (the time-transformed methods slow down there instead). The ray is captured either
  // way; the secant in r puts the segment's end between the horizon and the capture radius,
  // where the tracer reports it, and keeps every point of the ray outside the horizon.
  if (this->radius(end) < this->HorizonRadius && this->CaptureRadius > this->HorizonRadius)
  {
    if (!d.interpolates)
      this->interpolateDenseStep();
    const double target = 0.5 * (this->HorizonRadius + this->CaptureRadius);
    double lo = d.tau, hi = tau, rLo = r, rHi = this->radius(end);
    for (int k = 0; k < 60; ++k)
    {
      const double t = std::clamp(lo + (hi - lo) * (rLo - target) / (rLo - rHi), lo, hi);
      end = d.at(t);
      const double rt = this->radius(end);
      tau = t;
      if (rt > this->HorizonRadius && rt <= this->CaptureRadius)
        break;
      if (rt > target)
      {
        lo = t;
        rLo = rt;
      }
      else
      {
        hi = t;
        rHi = rt;
      }
    }
  }
  this->S = end;
  this->Slope = tau == 1.0 ? d.toSlope : this->slope(end);
  this->Lambda = tau == 1.0 ? d.lambda0 + d.h : d.lambda0 + tau * d.h;
  d.tau = tau;
  this->finishSegment(seg, false);
}
}
