// A bounding-volume hierarchy over the scene objects' bounding balls: the scene asks it which
// objects a chord may reach and which object is nearest a point, in O(log n) node visits for
// scenes of small objects instead of one test per object. Private to the Tracing module.
#ifndef asrt_ObjectHierarchy_h
#define asrt_ObjectHierarchy_h

#include "AsrtTypes.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

namespace asrt
{
class ObjectHierarchy
{
public:
  /// A bounded object: its index in the scene and its bounding ball.
  struct Ball
  {
    std::uint32_t index = 0;
    Vec3 center = Vec3::Zero();
    double radius = 0;
  };

  /// Objects a leaf holds at most.
  static constexpr std::uint32_t kLeafSize = 4;
  /// Nodes a traversal keeps pending at most. Median splits halve a node's count, so the tree's
  /// depth is at most ⌈log2(n / kLeafSize)⌉ + 1 ≤ 32 for n < 2³², and a depth-first traversal that
  /// pushes both children holds at most one pending node a level plus the one it pops.
  static constexpr int kStackSize = 64;

  /// Replaces the hierarchy by one over `balls` (finite centres and radii). Each node splits its
  /// objects at the median of their centres along the axis on which the centres spread most.
  /// Throws InvalidParameter for 2³² balls or more.
  void build(std::vector<Ball> balls);
  bool empty() const { return this->Nodes.empty(); }

  /// A chord a → b with the ball that holds it (centre `mid`, radius `half`) and a bound `bend` on
  /// how far the segment's interpolant strays from it.
  struct Chord
  {
    Vec3 a, b, mid;
    double half = 0, bend = 0;
  };

  /// Calls visit(index) for every object that the chord may reach: whose bounding ball may come
  /// within `half` of `mid` (the scene's per-object ball test) and within `bend` of the chord (a
  /// hit lies on the interpolant or the chord, on the object, so in its ball). Culling is
  /// conservative: a node is skipped only if its box lies farther than `half` from `mid` by a
  /// margin (1e-8 relative, plus round-off of the coordinates) wider than the per-object test
  /// grants (1e-9 relative), or farther than `bend` from the chord by a margin wider than a
  /// refined hit's distance from its surface. Nodes are never skipped where squares could
  /// overflow or the chord is not finite. Allocation-free and thread-safe.
  template<class Visit>
  void visitNear(const Chord& chord, Visit&& visit) const;

  /// The least of `best` and value(index) over the objects, where value(index) must be at least
  /// the distance from x to that object's bounding ball. A node is pruned only if its box is
  /// farther from x than `best` by more than the round-off of the two distances, so the result is
  /// exactly the minimum over all objects. Nearer children are searched first. Allocation-free
  /// and thread-safe.
  template<class Value>
  double minimum(const Vec3& x, double best, Value&& value) const;

private:
  /// A box holding the balls of a contiguous range of Order, and their largest radius. A leaf
  /// (count > 0) holds Order[first, first + count); an inner node (count = 0) has its children at
  /// Nodes[first] and Nodes[first + 1].
  struct Node
  {
    Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();
    double maxRadius = 0;
    double scale = 0; ///< the largest |coordinate| of the box, for round-off bounds
    std::uint32_t first = 0, count = 0;
  };

  /// Squared distance from p to the node's box (0 inside).
  static double boxDistance2(const Node& n, const Vec3& p)
  {
    double d2 = 0;
    for (int i = 0; i < 3; ++i)
    {
      const double d = std::max({ n.lo[i] - p[i], p[i] - n.hi[i], 0.0 });
      d2 += d * d;
    }
    return d2;
  }
  static double largestCoordinate(const Vec3& p) { return p.cwiseAbs().maxCoeff(); }
  /// Whether the chord a + t·delta, t ∈ [0, 1], meets the node's box widened by `bend` and a
  /// margin: the slab test. A hit point lies within `bend` of the chord and on its object up to
  /// the refinement's tolerance (a few hundred ulps of the coordinates); the margin, 1e-9 of the
  /// coordinates, covers that and the round-off of the slab parameters many times over.
  static bool crossesSlabs(const Node& n, const Vec3& a, const Vec3& delta, double bend,
                           double chordScale)
  {
    const double widen = bend * (1.0 + 1e-6) + 1e-9 * (chordScale + n.scale);
    double t0 = 0.0, t1 = 1.0;
    for (int i = 0; i < 3; ++i)
    {
      const double lo = n.lo[i] - widen, hi = n.hi[i] + widen;
      if (delta[i] == 0.0)
      {
        if (a[i] < lo || a[i] > hi)
          return false;
        continue;
      }
      double ta = (lo - a[i]) / delta[i], tb = (hi - a[i]) / delta[i];
      if (ta > tb)
        std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
      if (t0 > t1)
        return false;
    }
    return true;
  }

  void split(std::vector<Ball>& balls, std::uint32_t node, std::uint32_t first, std::uint32_t count,
             int depth);

  std::vector<Node> Nodes;          ///< Nodes[0] is the root
  std::vector<std::uint32_t> Order; ///< object indices, leaf by leaf
};

template<class Visit>
void ObjectHierarchy::visitNear(const Chord& chord, Visit&& visit) const
{
  if (this->Nodes.empty())
    return;
  const Vec3& mid = chord.mid;
  const double half = chord.half, midScale = largestCoordinate(mid);
  const Vec3 delta = chord.b - chord.a;
  const bool finite = chord.a.allFinite() && chord.b.allFinite() && std::isfinite(chord.bend);
  const double chordScale = 1.0 + largestCoordinate(chord.a) + largestCoordinate(chord.b);
  std::uint32_t stack[kStackSize];
  int top = 0;
  stack[top++] = 0;
  while (top > 0)
  {
    const Node& n = this->Nodes[stack[--top]];
    // An object whose ball test passes lies within (r + half)(1 + 1e-9) of mid, so its ball, and
    // the box holding it, within half + (r + half)·1e-9 of mid; 1e-8 covers that and the
    // round-off of the squares, 1e-13 of the coordinates that of the box's corners.
    const double margin = 1e-8 * (half + n.maxRadius) + 1e-13 * (n.scale + midScale);
    const double reach = half + margin;
    // NaN compares false: such a chord reaches everything, as in the per-object test.
    if (half + n.maxRadius < 1e150 && boxDistance2(n, mid) > reach * reach)
      continue;
    if (finite && !crossesSlabs(n, chord.a, delta, chord.bend, chordScale))
      continue;
    if (n.count > 0)
    {
      for (std::uint32_t k = n.first; k < n.first + n.count; ++k)
        visit(this->Order[k]);
    }
    else
    {
      stack[top++] = n.first + 1;
      stack[top++] = n.first;
    }
  }
}

template<class Value>
double ObjectHierarchy::minimum(const Vec3& x, double best, Value&& value) const
{
  if (this->Nodes.empty())
    return best;
  const double xScale = largestCoordinate(x);
  // A node's lower bound: its box distance less the round-off of that distance and of a ball
  // distance |x − c| − r (a few ulps of the coordinates). NaN or an overflowed square gives 0,
  // so such a node is searched.
  auto bound = [xScale](const Node& n, const Vec3& p)
  {
    const double d2 = boxDistance2(n, p);
    if (!(d2 < 1e300))
      return 0.0;
    const double d = std::sqrt(d2);
    return d - 1e-9 * d - 1e-12 * (n.scale + xScale);
  };
  struct Pending
  {
    std::uint32_t node;
    double bound;
  };
  Pending stack[kStackSize];
  int top = 0;
  stack[top++] = { 0, bound(this->Nodes[0], x) };
  while (top > 0)
  {
    const Pending p = stack[--top];
    // Every ball in the node is at least p.bound away, and each value at least its ball's
    // distance: none can go below best.
    if (p.bound >= best)
      continue;
    const Node& n = this->Nodes[p.node];
    if (n.count > 0)
    {
      for (std::uint32_t k = n.first; k < n.first + n.count; ++k)
        best = std::min(best, value(this->Order[k]));
      continue;
    }
    const Pending a{ n.first, bound(this->Nodes[n.first], x) };
    const Pending b{ n.first + 1, bound(this->Nodes[n.first + 1], x) };
    // The nearer child is popped first, so that best falls early and prunes the farther.
    if (a.bound <= b.bound)
    {
      stack[top++] = b;
      stack[top++] = a;
    }
    else
    {
      stack[top++] = a;
      stack[top++] = b;
    }
  }
  return best;
}
}

#endif
