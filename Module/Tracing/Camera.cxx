#include "Camera.h"

#include <cmath>
#include <sstream>

namespace asrt
{
const char* toString(ObserverMotion m)
{
  return m == ObserverMotion::Static ? "static" : "zamo";
}

ObserverMotion observerMotionFromString(const std::string& s)
{
  if (s == "static")
    return ObserverMotion::Static;
  if (s == "zamo")
    return ObserverMotion::ZAMO;
  throw InvalidParameter("observer must be \"static\" or \"zamo\", got \"" + s + "\"");
}

namespace
{
void requireFinite3(const Vec3& v, const char* what)
{
  if (!v.allFinite())
  {
    std::ostringstream os;
    os << "camera " << what << " must be finite, got (" << v.transpose() << ")";
    throw InvalidParameter(os.str());
  }
}

double dot(const Mat4& g, const Vec4& a, const Vec4& b)
{
  return a.dot(g * b);
}
}

Camera::Camera(const Spacetime& st, const CameraParameters& params)
  : St(st)
  , Params(params)
{
  requireFinite3(params.position, "position");
  requireFinite3(params.focalPoint, "focal point");
  requireFinite3(params.viewUp, "view-up");
  requireFinite(params.viewAngle, "camera view angle");
  if (!(params.viewAngle > 0.0 && params.viewAngle < 180.0))
  {
    std::ostringstream os;
    os << "camera view angle must lie in (0, 180) degrees, got " << params.viewAngle;
    throw InvalidParameter(os.str());
  }
  if (params.width <= 0 || params.height <= 0)
  {
    std::ostringstream os;
    os << "camera resolution must be positive, got " << params.width << " x " << params.height;
    throw InvalidParameter(os.str());
  }
  const Vec3 f = params.focalPoint - params.position;
  if (!(f.norm() > 0.0))
    throw InvalidParameter("camera focal point coincides with its position");
  if (f.normalized().cross(params.viewUp).norm() < 1e-9 * params.viewUp.norm() ||
      params.viewUp.norm() == 0.0)
    throw InvalidParameter("camera view-up is zero or parallel to the direction of view");

  this->X << 0.0, params.position;
  const double r = st.radius(this->X);
  const double rPlus = st.outerHorizon();
  if (rPlus > 0.0 && !(r > rPlus))
  {
    std::ostringstream os;
    os << "camera at r = " << r << " M is inside the horizon r+ = " << rPlus
       << " M: no light from outside reaches it";
    throw InvalidParameter(os.str());
  }
  this->G = st.metric(this->X);
  const Mat4 ginv = st.inverseMetric(this->X);

  if (params.observer == ObserverMotion::Static)
  {
    // u = ∂_t / √(−g_tt): only where ∂_t is timelike.
    const double gtt = this->G(0, 0);
    if (!(gtt < 0.0))
    {
      std::ostringstream os;
      os << "no static observer at the camera position (g_tt = " << gtt
         << " >= 0: inside the ergosphere); use the \"zamo\" observer";
      throw InvalidParameter(os.str());
    }
    this->U = Vec4(1.0, 0.0, 0.0, 0.0) / std::sqrt(-gtt);
  }
  else
  {
    // Zero angular momentum observer: u_μ ∝ −∂_μ t_BL. The ingoing Kerr–Schild time is
    // t_KS = t_BL + ∫ (2Mr − Q²)/Δ dr, Δ = r² − 2Mr + a² + Q², so ∂_μ t_BL = δ⁰_μ − G'(r) ∂_μ r.
    Vec4 dr;
    st.radiusGradient(this->X, dr);
    const double M = st.mass(), a = st.spin(), Q = st.charge();
    const double Delta = r * r - 2.0 * M * r + a * a + Q * Q;
    const double Gp = (2.0 * M * r - Q * Q) / Delta;
    Vec4 dt = Vec4(1.0, 0.0, 0.0, 0.0) - Gp * dr;
    const double norm2 = dt.dot(ginv * dt);
    if (!(norm2 < 0.0))
      throw InvalidParameter("no zero-angular-momentum observer at the camera position");
    const Vec4 ulow = -dt / std::sqrt(-norm2);
    this->U = ginv * ulow;
  }

  // Spatial legs by Gram–Schmidt with the metric, from the camera's coordinate axes.
  auto orthonormalise = [&](Vec4 v, std::initializer_list<const Vec4*> against)
  {
    v += dot(this->G, this->U, v) * this->U; // remove the part along u (u·u = −1)
    for (const Vec4* e : against)
      v -= dot(this->G, *e, v) * (*e);
    return Vec4(v / std::sqrt(dot(this->G, v, v)));
  };
  const Vec3 fwd = f.normalized();
  const Vec3 upc = params.viewUp.normalized();
  this->Forward = orthonormalise(Vec4(0.0, fwd.x(), fwd.y(), fwd.z()), {});
  this->Up = orthonormalise(Vec4(0.0, upc.x(), upc.y(), upc.z()), { &this->Forward });
  const Vec3 rc = fwd.cross(upc);
  this->Right = orthonormalise(Vec4(0.0, rc.x(), rc.y(), rc.z()), { &this->Forward, &this->Up });
  this->TanHalf = std::tan(0.5 * params.viewAngle * M_PI / 180.0);
}

Vec3 Camera::localDirection(double i, double j) const
{
  const double aspect = static_cast<double>(this->Params.width) / this->Params.height;
  // (2i + 1 − W)/W is exactly antisymmetric under i → W − 1 − i, so mirrored pixels get mirrored
  // directions to the bit and symmetric scenes give symmetric images.
  const double W = this->Params.width, H = this->Params.height;
  const double x = (2.0 * i + 1.0 - W) / W * this->TanHalf * aspect;
  const double y = (2.0 * j + 1.0 - H) / H * this->TanHalf;
  return Vec3(x, y, 1.0).normalized();
}

PhasePoint Camera::pixelRay(double i, double j) const
{
  const Vec3 n = this->localDirection(i, j);
  const Vec4 dir = n.x() * this->Right + n.y() * this->Up + n.z() * this->Forward;
  // The photon that reaches the eye from direction n has k = u − n; the ray is traced backwards,
  // along −k = n − u (past-directed, leaving the eye towards what it sees), with E_local = 1.
  const Vec4 k = dir - this->U;
  PhasePoint z;
  z.x = this->X;
  z.p = this->G * k;
  return z;
}
}
