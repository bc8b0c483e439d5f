// Small value types shared by the numeric core. Plain C++ on Eigen: no VTK types here.
#ifndef asrt_AsrtTypes_h
#define asrt_AsrtTypes_h

#include <Eigen/Dense>

#include <stdexcept>
#include <string>

namespace asrt
{
using Vec3 = Eigen::Vector3d;
using Vec4 = Eigen::Vector4d;
using Mat4 = Eigen::Matrix4d;

/// A point of the cotangent bundle: coordinates x^μ = (t, x, y, z) in the spacetime's Cartesian
/// chart and the covariant momentum p_μ. Light rays live on H(x, p) = 0.
struct PhasePoint
{
  Vec4 x = Vec4::Zero();
  Vec4 p = Vec4::Zero();
};

/// Thrown for parameters that describe no valid physical or numerical set-up. The message names
/// the offending parameter and its value.
class InvalidParameter : public std::invalid_argument
{
public:
  using std::invalid_argument::invalid_argument;
};

/// Why a ray stopped. Every ray ends with exactly one of these.
enum class Termination
{
  Running = 0,      ///< not terminated yet
  Escaped,          ///< left the escape radius
  Captured,         ///< crossed r <= r_+ (1 + epsilon): fell into the hole
  StepBudget,       ///< used up its step budget
  NumericalFailure, ///< non-finite state, or an implicit solve that did not converge
  HitObject         ///< a visitor (scene intersection) stopped it
};

const char* toString(Termination t);

/// Throws InvalidParameter("<what> must be finite, got <v>") for NaN or infinity.
void requireFinite(double v, const char* what);

/// `v` in the fewest digits that read back as exactly `v` (std::to_chars' shortest form): two
/// different numbers in a message never print alike (1.000000000000001 is not "1").
std::string exactNumber(double v);
}

#endif
