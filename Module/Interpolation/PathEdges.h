// Moving edges along a movie path: the pixels near which the inner pair of keys disagree on what a
// pixel's ray ends on (another object, another image, another way of ending) cannot be predicted
// from the pixel's own records, but the scene points on either side of the edge can be followed.
//
//  - Motion. The scene points of both inner keys are matched to the other inner key
//    (matchFrames), and through the outer keys where those match too: each point's position in
//    the picture is then known at 2 to 4 keys and moves on the Lagrange polynomial through them
//    (cubic, quadratic or linear in s). Points seen in one inner key only move as matchFrames
//    extrapolates them from their matched neighbours.
//  - Coverage. A point covers at t the parallelogram its source pixel maps to, the unit square
//    through (1 − τ)·I + τ·D (D the match's Jacobian, τ the fraction of the way to the other inner
//    key). Where several cover a spot, the lowest image order, then the shortest path, is in
//    front, as in the splat interpolator.
//  - Shading. The front point's (u, v), moved within its pixel by the surface Jacobian mapped to
//    t, is shaded with the footprint filter at 3×3 sub-positions of the pixel, whose mean is the
//    pixel's colour: an edge crossing the pixel then blends as a supersampled trace does.
//  - The keys' own residual. A key's points cover the unit squares of their pixels, so the edges
//    they move lie on the key's pixel grain, wherever within the pixel the key saw the edge. The
//    key's traced colour of a pixel an edge crosses holds that place (its anti-aliasing): its
//    difference to what the key's own points show at the pixel's 3×3 sub-positions is the
//    residual of the grain. A moved pixel an edge crosses at t takes a share of the mean residual
//    of the key pixels whose points cover its sub-positions (PathOptions::keyResidualShare): the
//    edge carried with its points carries its place within the pixel too, roughly, the pixels at t
//    not lying where the key's did. On the mass ramp's study frames (bench/REPORT.md) the plain
//    frames against the traced ones gain 0.6–1.7 dB with a share of 0.6 (0.45 and 0.8 within
//    0.3 dB of it; 1.4 gains or loses up to 0.5 dB); in the tests the moved-edge pixels gain
//    2.7 dB. The carried share holds only in part, by about the residual's own size: its squared
//    colour difference adds to the pixel's estimate (the study's shares for 40 dB 0.1–0.5 %
//    lower).
//  - Hedging. The points of both inner keys, and each inner key's alone, move the edge three
//    ways; where the keys lie far apart these disagree on where it is now. The pixel's colour is
//    then the mean of the ways that cover it: a softened edge, whose expected squared error is
//    below that of any one way placed wrong (on the mass ramp, keys 0.11 M apart, the plain
//    frames gain 0.4–1.2 dB against converged ones).
//  - The shadow's rim. A spot that a surface's moved points cover and the hole's moved rays cover
//    too may show either at t: the shadow grows or shrinks with the path (a mass ramp's swallows
//    the images near its rim), and the surface's points, near the photon ring, move least
//    predictably. Where asked (hedgeNearShadow, for a frame shown as predicted), the spot takes
//    the mean of the two colours and the pixel's estimate is at least the squared error that mean
//    leaves where the other shows (on the mass ramp, keys 0.11 M apart, the plain frames gained
//    1.1 dB on average against the traced ones; on the Kerr spin ramp, whose hole shrinks, the
//    plain previews 2.1 dB against converged ones). Where the caller gives the path's spacetime
//    and the hole grows between the inner keys, the horizon places what it swallows (below) and
//    the rim is not hedged: on the mass ramp the mean then cost 0.6 dB.
//  - The horizon. Where the caller knows the spacetime at t (PathOptions::spacetimeAt), a moved
//    point whose scene point lies inside the hole's outer horizon at t shows the hole instead: a
//    hole that grows along the path swallows the parts of the surfaces that reach into it (Fig.
//    4's cylinders run through the hole), and those points, seen by one inner key and gone at the
//    other, move only as matchFrames extrapolates them. On the mass ramp, keys 0.11 M apart, the
//    plain preview gains 1.1 dB against converged frames (27.3 → 28.5 dB), the plain frame
//    2.2 dB; the hedge of the shadow's rim, which stood in for it there, is then left off.
//  - Estimate. The same pixel predicted other ways: with linear motion (the inner pair alone),
//    from each inner key's points alone, and, where the inner pair agree on the pixel itself,
//    per pixel. The largest squared colour difference to the prediction, levels² of 255 summed
//    over the channels, is the estimate; what no prediction reaches stays to be re-traced. The
//    ways may all move an edge alike and still misplace it by a fraction of a pixel (the keys
//    place it only to their pixels' grain), which changes the pixel by that fraction of the
//    contrast across it: so the estimate is also at least a quarter of the squared difference
//    to what the moved points show at the centres of the 8 neighbours. Where every moved point
//    within a pixel of it (its sub-positions, its 8 neighbours' centres) ends alike with its
//    centre's, no edge lies there at t and that contrast is the texture's: such a pixel is a way
//    of predicting of its own (PathMethod::MovedSurface), whose probes calibrate its estimate
//    apart from the pixels an edge crosses, whose errors are rarer and larger. Its contrast is
//    taken at the 8 points half a pixel from its centre, as far as a misplacement of half a pixel
//    brings the texture, not at the neighbours' centres: a pixel within one square of a checker
//    is then estimated exact, as it is. On the mass ramp's study frames (bench/REPORT.md) the
//    moved-surface pixels' estimate ranks their error at Spearman 0.74–0.84, against 0.50–0.77
//    from the neighbours' centres, and every such pixel estimated exact was exact. Across an edge
//    the quarter holds where the ways dispute what the pixel's centre shows (another surface or
//    none through the inner pair alone or either key's points alone, or the hole's moved rays
//    covering a surface shown there): on the mass ramp, keys 0.11 and 0.055 M apart, 19–39 % of
//    such pixels showed another surface than traced at their centre, against 0.3–2.4 % of the
//    others. Where every way shows the centre alike, the edge lies within about a quarter of a
//    pixel of where they put it, and a sixteenth of the contrast counts. Across an edge the pixel
//    shows at t what one of the inner keys shows there (the edge swept over it one way), give or
//    take the texture's motion: the squared difference to the nearer of their colours there, a
//    colour the prediction made up (a blend, a third surface), is an error of another source and
//    adds to the estimate. On the mass ramp's study frames (bench/REPORT.md), keys 0.055 M apart,
//    it lowered the share the estimate's order needs for 35 dB from 2.3–7.9 % to 1.6–6.9 %.
// Private to ASRT::Interpolation. Deterministic: the result does not depend on the thread count.
#ifndef asrt_PathEdges_h
#define asrt_PathEdges_h

#include "FrameMatching.h"
#include "PathInterpolation.h"

#include <vector>

namespace asrt
{
/// One pixel predicted by moving the scene points of the keys.
struct MovedEdgePixel
{
  bool covered = false; ///< false: no point covers the pixel at t (it must be re-traced)
  RayRecord record;     ///< the front point's at the pixel's centre, its colour the sub-samples'
  float estimate = 0;   ///< squared colour error summed over the channels
  /// Whether the moved points at the pixel's sub-positions and its 8 neighbours' centres all end
  /// alike with its centre's: no edge lies within a pixel of it at t (PathMethod::MovedSurface).
  bool oneSurface = false;
};

/// Predicts the listed pixels (indices into the frame) of the frame at t from the keys, the
/// inner pair (a, a + 1) bracketing t, the keys' scene points matched with the searches `index`
/// makes. `perPixel[k]` is the per-pixel prediction of pixel `pixels[k]`, or null where the inner
/// pair disagree on it. `hedged`: the colour is the mean of the ways of moving (Hedging above),
/// else that of both inner keys' points. `hedgeNearShadow`: the shadow's rim hedged (above).
/// `cache` (if given) keeps the keys' correspondences between calls. `along` (if given): the
/// path's spacetime, whose horizon at t hides the scene points inside it (The horizon, above).
/// `residualShare`: the share of the keys' own residual an edge pixel takes (The keys' own
/// residual, above; 0: none).
std::vector<MovedEdgePixel> predictMovedEdges(
  const std::vector<PathKey>& keys, std::size_t a, double t, int width, int height,
  const Scene& scene, const PointIndexFactory& index, const std::vector<std::int32_t>& pixels,
  const std::vector<const RayRecord*>& perPixel, bool hedged, bool hedgeNearShadow,
  PathMatchCache* cache, const SpacetimeAlongPath& along, double residualShare);
}

#endif
