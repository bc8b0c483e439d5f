// Tracing a frame: one ray per pixel through the scene, in parallel, each ending in a RayRecord.
#ifndef asrt_FrameTracer_h
#define asrt_FrameTracer_h

#include "AdaptiveGrid.h"
#include "RayRecord.h"
#include "SceneDescription.h"
#include "asrtTracingModule.h"

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <unordered_map>
#include <utility>
#include <vector>

namespace asrt
{
class PixelLookup;

/// Fewer rays than this are traced on the calling thread alone: each costs about as much as waking
/// the other threads, and on a busy machine that wake-up costs far more (OpenMP's waiting threads
/// spin). A list of pixels that each take several rays (lattice blocks, anti-aliased pixels) counts
/// them at kRaysPerItem.
constexpr long kParallelRays = 16;
constexpr long kRaysPerItem = 8;
/// Passes over records that trace nothing run in parallel above this many records.
constexpr long kParallelRecords = 16384;

/// The edge neighbours of `pixels` inside a width × height frame that are not among them, sorted,
/// each once: the pixels whose centre rays FrameTracer::tracePixels traces besides those asked for
/// (with a grid lattice above 1, traceCentres processes the lattice blocks holding them whole).
ASRTTRACING_EXPORT std::vector<std::pair<int, int>> edgeNeighbours(
  const std::vector<std::pair<int, int>>& pixels, int width, int height);

/// The centre rays, in a whole frame's records (row-major, width × height), of the edge neighbours
/// of `pixels` (edgeNeighbours, in its order): the border beside which those pixels' records are
/// the frame's own (FrameTracer::tracePixelsBeside, FrameTracer::antialiasAgain).
ASRTTRACING_EXPORT std::vector<JacobianSample> edgeNeighbourSamples(
  const std::vector<RayRecord>& frame, int width, int height,
  const std::vector<std::pair<int, int>>& pixels);

/// The edge neighbours of `pixels` (edgeNeighbours) that FrameTracer::tracePixelsBeside traces:
/// those `border` gives no sample for.
ASRTTRACING_EXPORT std::vector<std::pair<int, int>> neighboursToTrace(
  const std::vector<std::pair<int, int>>& pixels, int width, int height,
  const std::vector<JacobianSample>& border);

/// Centre rays that FrameTracer::tracePixels traced, kept for later calls on the same tracer: a
/// centre ray depends on its pixel alone, so a pixel asked for again, or traced before as the
/// neighbour of one asked for, is taken from here instead of traced again, and the records come
/// out the same bit for bit. Kept only on grid lattice 1 (scattered pixels); above it the lattice
/// blocks are traced whole and nothing is kept. Not to be shared by calls running at once.
class ASRTTRACING_EXPORT CentreRays
{
public:
  /// How many centre rays are kept.
  std::size_t size() const { return this->Records.size(); }

private:
  friend class FrameTracer;
  std::unordered_map<std::int64_t, RayRecord> Records; ///< by j · width + i, before Jacobians
};

/// Traces pixels of one scene. Thread-safe: every traced pixel uses its own propagator.
class ASRTTRACING_EXPORT FrameTracer
{
public:
  /// Builds the spacetime and camera of the description; throws InvalidParameter if they are
  /// invalid (camera inside the horizon, static observer in an ergosphere, bad method, ...).
  explicit FrameTracer(const SceneDescription& scene);
  ~FrameTracer();

  const Spacetime& spacetime() const { return *this->St; }
  const Camera& camera() const { return *this->Cam; }
  const SceneDescription& description() const { return this->Desc; }
  /// The escape radius actually used: at least the scene's, the celestial sphere's and the eye's.
  double escapeRadius() const { return this->Tracing.escapeRadius; }
  /// Whether propagators may cross the scene's far field in one segment (on by default; see
  /// FarField). Off, every segment follows the ray: for comparisons.
  void setFarField(bool enabled);

  /// Every ray this tracer has integrated since it was made, whatever it was for: the centre rays
  /// of the pixels asked for and of the neighbours tracePixels and traceRows trace and drop, the
  /// adaptive grid's points, anti-aliasing samples and edge midpoints, single rays (tracePixel,
  /// traceAt). A record's raysPerPixel counts only the rays charged to its own pixel. Over a whole
  /// frame traced a ray a pixel (grid lattice 1) they add up to this count; they leave out the
  /// dropped neighbours' centre rays and the midpoint rays charged to them, and on the adaptive
  /// grid the rays a lattice block traced on its border, or in a neighbour's middle row or column
  /// (AdaptiveGrid.h), where the block owning that pixel filled it. Calls on one tracer at the
  /// same time add to the one count.
  std::int64_t raysIntegrated() const { return this->RaysIntegrated.load(); }

  /// Traces one pixel; appends its polyline to `path` if given.
  RayRecord tracePixel(int i, int j, std::vector<PathPoint>* path = nullptr) const;

  /// Traces the ray through the continuous screen position (x, y), where pixel (i, j) is the
  /// position (i, j) (Camera::localDirection's convention): sub-pixel rays, e.g. to check where
  /// an interpolated point should be. The record's pixel is (x, y) rounded; no Jacobian (NaN).
  RayRecord traceAt(double x, double y) const;

  /// Traces the given pixels (i, j) with OpenMP, dynamically scheduled (rays near the photon
  /// sphere cost far more than the rest), and anti-aliases them as the description's rendering
  /// says (antialias()). Their edge neighbours in the frame (edgeNeighbours()) are traced too (and
  /// dropped), so that each record, Jacobian and colour included, is the whole frame's record of
  /// that pixel: raysIntegrated() counts their rays, the records' raysPerPixel do not. The
  /// result is in the order given and identical for any number of threads. `progress` is called
  /// now and then with the fraction done; if it returns false the work stops early and the
  /// returned records of untraced pixels keep termination Running.
  std::vector<RayRecord> tracePixels(const std::vector<std::pair<int, int>>& pixels,
                                     const std::function<bool(double)>& progress = nullptr) const;
  /// As above, the centre rays found in `kept` taken from there, and those traced added to it
  /// (CentreRays): raysIntegrated() counts only the centre rays traced now.
  std::vector<RayRecord> tracePixels(const std::vector<std::pair<int, int>>& pixels,
                                     CentreRays& kept,
                                     const std::function<bool(double)>& progress = nullptr) const;

  /// tracePixels, with the edge neighbours' centre rays read from `border` (at most one sample a
  /// pixel, none on one of `pixels`) instead of traced: each record's Jacobian and anti-aliasing
  /// judgement read them as they would the neighbours' own rays. Neighbours missing from `border`
  /// are traced and dropped as tracePixels traces them. With the neighbours' own centre rays as
  /// `border` the records are tracePixels' bit for bit; with others (a prediction of them) the
  /// records' rays are still their own, their Jacobians and colours follow the samples given.
  /// The centre rays found in `kept` (if given) are taken from there and those traced added.
  /// Throws InvalidParameter for a border sample outside the frame, on one of the pixels, or
  /// given twice.
  std::vector<RayRecord> tracePixelsBeside(
    const std::vector<std::pair<int, int>>& pixels, const std::vector<JacobianSample>& border,
    CentreRays* kept = nullptr, const std::function<bool(double)>& progress = nullptr) const;

  /// The centre rays of tracePixels alone: point-sampled colours, one ray a pixel, Jacobians from
  /// the neighbours among these pixels. For callers that complete the Jacobians with neighbours
  /// traced elsewhere before anti-aliasing (row bands, other processes). With a grid lattice
  /// above 1 (AntialiasOptions::gridLattice) most records are interpolated (AdaptiveGrid.h),
  /// the same in any split of the frame.
  std::vector<RayRecord> traceCentres(const std::vector<std::pair<int, int>>& pixels,
                                      const std::function<bool(double)>& progress = nullptr) const;

  /// Anti-aliases records traced by traceCentres whose Jacobians are complete, as the
  /// description's rendering says (Antialiasing.h): filters their textures over their
  /// footprints, and traces the extra rays of the pixels that need them. A pixel is judged by its
  /// 4 edge neighbours among the records and `neighbours`; the judgement reads only their centre
  /// rays (JacobianSample), so pieces of a frame anti-aliased with their bordering rows as
  /// neighbours assemble bit for bit into the whole frame. Only colours and raysPerPixel change.
  /// Returns false if `progress` (as tracePixels') asked to stop; the colours are then incomplete.
  bool antialias(std::vector<RayRecord>& records,
                 const std::vector<JacobianSample>& neighbours = {},
                 const std::function<bool(double)>& progress = nullptr) const;

  /// A whole frame traced with the rendering `tracedWith`, anti-aliased again into this tracer's
  /// frame: bit for bit the frame traceRows would trace, for the extra rays of its sampled pixels
  /// and edge midpoints alone. It holds where the two renderings differ only in the adaptive cap
  /// and this one's pattern has an even side (adaptivePatternSide): adaptive sampling judges a
  /// pixel by centre rays and edge midpoints alone, the same at any cap of two or more rays a
  /// side, and a pattern of even side takes no colour from the centre ray, whose colour the
  /// first anti-aliasing overwrote. `frame` is whole and row-major, as traceRows gives it. Throws
  /// InvalidParameter otherwise, naming what differs; returns false if `progress` asked to stop
  /// (the colours are then incomplete).
  bool antialiasAgain(std::vector<RayRecord>& frame, const AntialiasOptions& tracedWith,
                      const std::function<bool(double)>& progress = nullptr) const;
  /// As above, for the pixels of `frame` at the indices `pixels` alone (each once): their records
  /// as the whole frame anti-aliased again would give them, bit for bit, in the order given,
  /// judged against their edge neighbours' centre rays in `frame` (edgeNeighbourSamples). Throws
  /// InvalidParameter as above, and for an index outside the frame or given twice.
  std::vector<RayRecord> antialiasAgain(const std::vector<RayRecord>& frame,
                                        const AntialiasOptions& tracedWith,
                                        const std::vector<std::int32_t>& pixels) const;

  /// All pixels of rows [rowBegin, rowEnd), row-major from the bottom-left. The rows just outside
  /// the band are traced too (and dropped) so that the Jacobians and the anti-aliasing of a band
  /// are those of the whole frame: pieces assemble into exactly the single-piece frame.
  std::vector<RayRecord> traceRows(int rowBegin, int rowEnd,
                                   const std::function<bool(double)>& progress = nullptr) const;

  /// Fills the screen-space Jacobians of the records from their neighbours among them and among
  /// `neighbours` (pixels traced elsewhere, e.g. by another process). Where a pixel appears
  /// twice, its first appearance counts, records before neighbours. Interpolated records (traced
  /// false) keep the Jacobian of their interpolant.
  static void computeJacobians(std::vector<RayRecord>& records,
                               const std::vector<JacobianSample>& neighbours = {});

private:
  /// Traces the pixels' centre rays, keeps the first `keep` and anti-aliases them with the rest
  /// (their neighbours) and `border` as bordering samples.
  std::vector<RayRecord> traceKeeping(const std::vector<std::pair<int, int>>& pixels,
                                      std::size_t keep, const std::function<bool(double)>& progress,
                                      CentreRays* kept = nullptr,
                                      const std::vector<JacobianSample>& border = {}) const;
  /// traceCentres, the centre rays in `kept` (if given) taken from there and those traced added,
  /// the Jacobians read from `neighbours` too where the pixels border them.
  std::vector<RayRecord> traceCentresKept(const std::vector<std::pair<int, int>>& pixels,
                                          const std::function<bool(double)>& progress,
                                          CentreRays* kept,
                                          const std::vector<JacobianSample>& neighbours = {}) const;
  /// The adaptive judgement of antialias(): sets side[k] to `adaptiveSide` for the records to
  /// sample, bendOnly[k] where a footprint that bends is the only reason, and counts in
  /// midpointRays[k] the edge-midpoint rays it traced on their behalf. `lookup` holds the records
  /// and their bordering samples.
  void judgePixels(const std::vector<RayRecord>& records, const PixelLookup& lookup,
                   int adaptiveSide, std::vector<int>& side, std::vector<int>& midpointRays,
                   std::vector<unsigned char>& bendOnly) const;
  /// The centre records of traceCentres on the adaptive grid (AdaptiveGrid.h): the whole lattice
  /// blocks holding the pixels are processed, in parallel, and the pixels' records handed out.
  std::vector<RayRecord> traceGrid(const std::vector<std::pair<int, int>>& pixels,
                                   const std::function<bool(double)>& progress) const;
  struct GridWork;
  /// Traces a block's 9 points into `work`, then fills it if smooth (bilinear, or biquadratic
  /// where its quarters' centres agree) or refines its 4 quarters.
  void refineBlock(Propagator& prop, const GridBlock& b, GridWork& work) const;
  /// The ray of pixel (i, j) of the block `work` holds, traced on first use.
  const RayRecord& gridRay(Propagator& prop, int i, int j, GridWork& work) const;
  /// The ray of pixel (i, j) from the rays lattice blocks share, traced on first use.
  const RayRecord& sharedGridRay(Propagator& prop, int i, int j, GridWork& work) const;
  /// Whether a point of an edge neighbour's line of points nearest to lattice block `b` (its
  /// middle row or column) ends otherwise than in the hole.
  bool capturedBesideOtherEndings(Propagator& prop, const GridBlock& b, GridWork& work) const;
  /// The ray through screen position (x, y) with the given propagator (one per thread).
  RayRecord traceThrough(Propagator& prop, double x, double y) const;
  /// The colour a centre ray's sample shows without filtering (the texture at its hit, the horizon,
  /// the background or the failure colour).
  Color pointColor(const JacobianSample& s) const;

  SceneDescription Desc;
  std::unique_ptr<Spacetime> St;
  std::unique_ptr<Camera> Cam;
  TraceOptions Tracing;
  // On a cache line of its own: every ray of every thread adds to it, and the members above are
  // read by every ray.
  alignas(64) mutable std::atomic<std::int64_t> RaysIntegrated{ 0 };
};
}

#endif
