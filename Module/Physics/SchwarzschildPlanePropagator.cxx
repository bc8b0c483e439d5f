#include "SchwarzschildPlanePropagator.h"

#include <algorithm>
#include <cmath>

namespace asrt
{
SchwarzschildPlanePropagator::SchwarzschildPlanePropagator(const Spacetime& st, int order,
                                                           double step, Splitting splitting)
  : St(st)
  , M(st.mass())
  , Order(order)
  , Step(step)
  , Split(splitting)
{
  if (st.kind() != SpacetimeKind::Schwarzschild)
  {
    throw InvalidParameter("the Schwarzschild splitting models Schwarzschild only, not " +
                           st.name());
  }
  yoshidaWeights(order); // validates the order
}

void SchwarzschildPlanePropagator::start(const PhasePoint& z)
{
  const Vec3 X = z.x.tail<3>();
  const Vec3 P = z.p.tail<3>();
  const double r = X.norm();
  this->E1 = X / r;
  // The plane holds x and the spatial momentum; L⃗ = x × p is its normal (KS spatial slices are flat
  // in their angular part, so this is the conserved angular momentum).
  Vec3 Lvec = X.cross(P);
  this->L = Lvec.norm();
  if (this->L > 1e-300 * r * P.norm())
  {
    this->E2 = Lvec.cross(this->E1).normalized();
  }
  else
  {
    // Radial ray: any plane through it will do.
    const Vec3 trial = std::abs(this->E1.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
    this->E2 = (trial - trial.dot(this->E1) * this->E1).normalized();
    this->L = 0.0;
  }
  this->E = -z.p[0];
  this->R.reset(r);
  this->Phi.reset(0.0);
  // Ingoing Kerr–Schild to Schwarzschild: t_KS = t + 2M ln|r/2M − 1|, so p_r = p_r^KS − 2ME/(r −
  // 2M).
  const double prKS = this->E1.dot(P);
  this->Pr.reset(prKS - 2.0 * this->M * this->E / (r - 2.0 * this->M));
  this->T = z.x[0] - 2.0 * this->M * std::log(std::abs(r / (2.0 * this->M) - 1.0));
  this->Lambda = 0.0;
  this->Evaluations = 0;
  this->Current = this->state();
  this->tangent(this->Current, this->CurrentTangent);
}

PhasePoint SchwarzschildPlanePropagator::state() const
{
  const double r = this->R.value, phi = this->Phi.value;
  const double c = std::cos(phi), s = std::sin(phi);
  const Vec3 n = c * this->E1 + s * this->E2;
  const Vec3 ephi = -s * this->E1 + c * this->E2;
  const double prKS = this->Pr.value + 2.0 * this->M * this->E / (r - 2.0 * this->M);
  PhasePoint z;
  z.x[0] = this->T + 2.0 * this->M * std::log(std::abs(r / (2.0 * this->M) - 1.0));
  z.x.tail<3>() = r * n;
  z.p[0] = -this->E;
  z.p.tail<3>() = prKS * n + (this->L / r) * ephi;
  return z;
}

void SchwarzschildPlanePropagator::tangent(const PhasePoint& z, Vec4& dxds) const
{
  // dx/ds = r ∂H/∂p in the Cartesian chart.
  Vec4 dHdx;
  this->St.gradient(z.x, z.p, dHdx, dxds);
  dxds *= this->R.value;
}

void SchwarzschildPlanePropagator::strangFlatExact(double h)
{
  const double M = this->M, E = this->E;
  // K_A(d): r fixed; p_r gets −∂K_A/∂r = −2E²M²/(r − 2M)², t gets ∂K_A/∂p_t = 2EMr/(r − 2M).
  auto kick = [&](double d)
  {
    const double r = this->R.value, rm = r - 2.0 * M;
    this->Pr.add(-d * 2.0 * E * E * M * M / (rm * rm));
    this->T += d * 2.0 * E * M * r / rm;
    ++this->Evaluations;
  };
  // K_B(d): ṙ = −2M p_r with p_r constant.
  auto drift = [&](double d) { this->R.add(-2.0 * M * this->Pr.value * d); };
  // K_flat(d), exactly. K_flat = r(p_r² − E²)/2 + L²/(2r) keeps its value k along its own flow,
  // and k ≠ 0 off the flat light cone (the other flows carry −k). With ṙ = r p_r this gives
  // ṙ² = E²r² + 2kr − L², hence r̈ = E²r + k: r(s) = −k/E² + (r₀ + k/E²) cosh Es + (r₀p_r₀/E) sinh
  // Es. Then λ = ∫r ds and t = E λ in closed form, and φ = ∫L/r ds through τ = tanh(Es/2): Δφ = 2
  // atan2(A τ β, β² + (Aτ + B)B) with A = r₀ + 2k/E², B = r₀p_r₀/E, β = L/E, since the quadratic's
  // discriminant AC − B² is exactly β² on the level set.
  auto line = [&](double d)
  {
    const double r0 = this->R.value, pr0 = this->Pr.value, L = this->L;
    const double k = 0.5 * r0 * (pr0 * pr0 - E * E) + 0.5 * L * L / r0;
    const double x = E * d;
    // One sinh and one sqrt give all of sinh x, cosh x − 1 (without cancelling) and tanh(x/2).
    const double half = std::sinh(0.5 * x), chHalf = std::sqrt(1.0 + half * half);
    const double sh = 2.0 * half * chHalf;
    const double chm1 = 2.0 * half * half;
    const double shmx = std::abs(x) < 1e-3 ? x * x * x / 6.0 * (1.0 + x * x / 20.0) : sh - x;
    const double kE = k / (E * E);
    const double B = r0 * pr0 / E;
    // Both r and p_r advance by increments (p_r₁ − p_r₀ = (ṙ₁ − p_r₀ r₁)/r₁ expanded so no O(1)
    // terms cancel), which the compensated sums then add without losing their low bits.
    const double dr = (r0 + kE) * chm1 + B * sh;
    const double r1 = r0 + dr;
    const double dpr = (E * (r0 + kE) * sh + r0 * pr0 * chm1 - pr0 * dr) / r1;
    this->R.add(dr);
    this->Pr.add(dpr);
    const double beta = L / E, A = r0 + 2.0 * kE, tau = half / chHalf;
    this->Phi.add(2.0 * std::atan2(A * tau * beta, beta * beta + (A * tau + B) * B));
    const double dl = (r0 * sh + kE * shmx + B * chm1) / E;
    this->Lambda += dl;
    this->T += E * dl;
  };
  kick(0.5 * h);
  drift(0.5 * h);
  line(h);
  drift(0.5 * h);
  kick(0.5 * h);
}

void SchwarzschildPlanePropagator::strangRadial(double h)
{
  const double M = this->M, E2 = this->E * this->E, L2 = this->L * this->L;
  // K₁(h/2): r fixed. λ, φ and t are advanced here only, since only K₁ depends on their
  // conjugates (and dλ/ds = r is attributed to a single flow).
  auto kick = [&](double d)
  {
    const double r = this->R.value, rm = r - 2.0 * M;
    this->Pr.add(-d * (-E2 * (r * r - 4.0 * M * r) / (2.0 * rm * rm) - L2 / (2.0 * r * r)));
    this->Phi.add(d * this->L / r);
    this->T += d * this->E * r * r / rm;
    this->Lambda += d * r;
    ++this->Evaluations;
  };
  // K₂(d): exact solution of ṙ = r p_r, ṗ_r = −p_r²/2.
  auto scale = [&](double d)
  {
    const double r = this->R.value, pr = this->Pr.value;
    const double e = 0.5 * pr * d, q = 1.0 + e;
    this->R.add(r * e * (2.0 + e));
    this->Pr.add(-pr * e / q);
  };
  // K₃(d): ṙ = −2M p_r with p_r constant.
  auto drift = [&](double d) { this->R.add(-2.0 * M * this->Pr.value * d); };
  kick(0.5 * h);
  scale(0.5 * h);
  drift(h);
  scale(0.5 * h);
  kick(0.5 * h);
}

bool SchwarzschildPlanePropagator::advance(Segment& seg)
{
  const double M = this->M;
  // The step starts where the previous one ended: its Cartesian state and tangent are cached.
  seg.x0 = this->Current.x;
  seg.p0 = this->Current.p;
  seg.lambda0 = this->Lambda;
  seg.dl0 = this->R.value; // dλ/ds = r, times h below
  const Vec4 v0 = this->CurrentTangent;
  // Near the horizon the flows are large and nearly cancel (ṙ = r p_r − 2M p_r), so a single one
  // could carry r across r = 2M, where the chart ends. The step is therefore limited so that no
  // flow moves r by more than half its distance to 2M: h ≤ ½(r − 2M)/max(r E, r |p_r|). Away
  // from the horizon this bound exceeds any useful h (it is ≈ 1/(2E)) and the map is the
  // fixed-step symplectic one; near it, r approaches 2M geometrically until the tracer captures.
  const double speed = this->R.value * std::max(std::abs(this->Pr.value), std::abs(this->E));
  const double limit = 0.5 * (this->R.value - 2.0 * M) / std::max(speed, 1e-300);
  double maxWeight = 0.0;
  for (double w : yoshidaWeights(this->Order))
    maxWeight = std::max(maxWeight, std::abs(w));
  const double h = std::min(this->Step, limit / maxWeight);
  for (double w : yoshidaWeights(this->Order))
  {
    if (this->Split == Splitting::FlatExact)
      this->strangFlatExact(w * h);
    else
      this->strangRadial(w * h);
  }
  if (!(this->R.value > 2.0 * M) || !std::isfinite(this->Pr.value) ||
      !std::isfinite(this->Phi.value))
  {
    return false;
  }
  this->Current = this->state();
  this->tangent(this->Current, this->CurrentTangent);
  seg.x1 = this->Current.x;
  seg.p1 = this->Current.p;
  seg.lambda1 = this->Lambda;
  seg.d0 = h * v0;
  seg.d1 = h * this->CurrentTangent;
  seg.dl0 *= h;
  seg.dl1 = h * this->R.value;
  return std::isfinite(seg.x1[1]) && std::isfinite(seg.p1[1]);
}
}
