// MovieMaker's machinery (GeodesicMovie.h): its state between calls (MovieMaker::Internals) and
// the ways it gets a frame's records (MovieMaking): kept in memory, read from the store, traced,
// anti-aliased again or interpolated, with the bookkeeping of rays, pictures and probes that goes
// with them. Private to the movie's sources (GeodesicMovie.cxx, GeodesicMovieMaking.cxx).
#ifndef asrt_GeodesicMovieMaking_h
#define asrt_GeodesicMovieMaking_h

#include "GeodesicMovie.h"

#include "FrameTracer.h"
#include "LeaveOneOut.h"
#include "PathInterpolation.h"
#include "RayStore.h"
#include "SettingsError.h"

#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace asrt
{
/// completePathFrame's default probe share, the floor of the estimate.
constexpr double kMovieProbeFraction = 0.01;

/// What completePathFrame asked of the store alone did not have.
struct NotServed
{
};

/// How a movie's interpolated frames are made, as recorded with their keys in the store
/// (RayStore::recordInterpolatedFrame): the same keys and recipe make the same frame. `chained`:
/// the frame's pixels were also predicted through the pixels that the frames recorded between its
/// inner keys by the plain recipe re-traced (MovieMaker::Internals::chainSources).
std::string interpolationRecipe(const MovieSettings& settings, bool chained = false);

/// What a movie maker keeps between calls: the whole frames made and their rays, the pieces read
/// or traced for interpolated frames, the plan's measurements, and what the store holds of them.
struct MovieMaker::Internals
{
  std::map<int, std::vector<RayRecord>> whole; ///< whole frames made, in pixel order
  /// When each whole frame kept was last used (a count of uses): the least recent stored ones
  /// leave memory first (MovieMaking::keepWholeWithinBudget).
  std::map<int, std::uint64_t> lastUse;
  std::uint64_t uses = 0;
  /// The rays each whole frame made took: integrated if traced, its records' if read.
  std::map<int, double> wholeRays;
  /// Re-traced pixels kept in memory (MovieSettings::cacheRetraced), by retracedKey.
  std::map<std::pair<int, std::string>, std::vector<RayRecord>> retraced;
  std::optional<SceneDescription> shading; ///< the first frame's scene, textures loaded
  std::string shadingObjects;              ///< its text without what a path varies
  /// Frames the plan made from the store alone between the stored frames, with how: kept when the
  /// plan interpolates them between the same keys, until frame() hands them out (the same records
  /// it would make again).
  std::map<int, std::pair<std::vector<RayRecord>, MovieFrameReport>> served;
  /// The re-trace share estimate: the prior, then what the keys made measured.
  SpacingShareModel share;
  /// Whole frames' own errors against their converged pictures, once measured.
  std::map<int, SettingsError> settings;
  /// The store's id of each whole frame made, read or traced and stored.
  std::map<int, std::int64_t> storedIds;
  /// Interpolated frames the store records as made from keys that are frames of this movie, and
  /// stored: each is made again between exactly those keys, whatever keys the plan has.
  std::map<int, std::vector<int>> recorded;
  /// The frames of `recorded` that the store records by the plain recipe, as the plan found them:
  /// made between their keys alone. The pixels they re-traced join the chains of the frames made
  /// later between inner keys around them (PathOptions::samples), which are recorded as chained.
  /// Only these: they were made from their keys alone whenever they were made, and a frame is made
  /// so only where no such frame lies between its inner keys, so a chained frame made again finds
  /// the same samples, and the same pixels to re-trace, as when it was made. (Unless a later movie
  /// put new keys between its keys and made a frame there by the plain recipe, or another movie
  /// of the same rendering re-traced more pixels of the frames it runs through: it is then made
  /// again through those too, and traces the pixels that changes.)
  std::set<int> chainSources;
  /// The frames of `recorded` whose record is by the chained recipe: made through the chain
  /// sources' pixels.
  std::set<int> recordedChained;
  /// The chain sources' re-traced pixels, read from the store, for the frames between the inner
  /// keys of the frame made last.
  std::map<int, std::shared_ptr<const PathSamples>> samples;
  bool keysMade = false; ///< makeKeys() done: the plan is final
  /// Whole frames whose rays are counted in the maker's totals (read, traced or served as
  /// pictures): each counted once.
  std::set<int> wholeCounted;
  /// The rays the records of each interpolated frame's re-traced pixels hold, read or traced.
  std::map<int, double> heldRays;
  /// The keys' leave-one-out errors, for the frames between the same keys.
  std::shared_ptr<LeaveOneOutCache> leftOut = std::make_shared<LeaveOneOutCache>();
  /// Each whole frame's matchingFingerprint, once computed: the keys' leave-one-out errors are
  /// looked up by it for every frame between them. A frame's records are the same whenever it is
  /// made or read again.
  std::map<int, std::uint64_t> fingerprints;
  /// The rays each whole frame's records hold (their raysPerPixel), kept or let go.
  std::map<int, double> wholeHeldRays;
  /// Pictures of whole frames traced by this movie, encoded when traced
  /// (MovieSettings::encodePictures), until storedPictures() hands them out.
  std::map<int, std::vector<std::string>> pictures;
  std::deque<int> pictureOrder; ///< the frames of `pictures`, as they were traced
  std::set<int> encoded;        ///< the frames whose pictures were encoded when traced, each once
  /// Records of whole frames let go, their memory reused for the next frame traced: fresh memory
  /// costs its first touch (the kernel clears every page), memory used before does not.
  std::vector<RayRecord> spare;
  /// Whole frames made in this run (traced, or anti-aliased again; by this maker, or by the one it
  /// adopted them from, adoptWhole): reported as made, though the store holds them by the time
  /// the plan looks (the rendering's judgement makes the first and last frames before it).
  std::set<int> madeNow;
};

/// The ways the maker gets records, and the bookkeeping that goes with them.
struct MovieMaking
{
  MovieMaker& maker;
  MovieMaker::Internals& in;

  /// Whether the movie was asked to stop.
  bool cancelled() const;

  /// The tracers' progress callback: reports to the movie's and asks it whether to go on.
  std::function<bool(double)> progress() const;

  /// The frame's scene with its textures: the first frame's objects and textures, read once,
  /// where the frame's text differs from the first's only in what a path varies (the hole, the
  /// camera, the integrator, the rendering); else read from its own text.
  SceneDescription withTextures(const MovieFrame& f) const;

  /// A whole frame's records, in pixel order: kept, read from the store, or traced (and stored).
  const std::vector<RayRecord>& whole(int k);

  /// Whole frame k made by this movie (traced, or anti-aliased again), `rays` integrated in
  /// `took`: checked, counted, stored with its pictures, and kept; where it was `stored` as it
  /// was traced (traceStreamed, which checked it), only counted and kept.
  const std::vector<RayRecord>& keepMade(int k, std::vector<RayRecord> records, double rays,
                                         std::chrono::steady_clock::duration took,
                                         std::optional<std::int64_t> stored = std::nullopt);

  /// Traces whole frame k into `records` (one for each pixel; every one written) while the
  /// store's write, on a thread of its own, streams the rows already traced
  /// (MovieSettings::checkTraced run before the last row goes), and returns the stored frame's id,
  /// or that of a copy another writer stored meanwhile. Throws MovieCancelled when the movie is
  /// asked to stop, and the tracer's or the check's exception, with nothing stored.
  std::int64_t traceStreamed(int k, const FrameTracer& tracer, std::vector<RayRecord>& records);

  /// Whole frame k anti-aliased again from `records`, the same frame traced with the rendering
  /// `fromRendering` (FrameTracer::antialiasAgain): checked, counted, stored and kept as a frame
  /// this movie traced, for the rays of its sampled pixels alone.
  const std::vector<RayRecord>& derivedWhole(int k, std::vector<RayRecord> records,
                                             const AntialiasOptions& fromRendering);

  /// Keeps whole frame k, counted once among the movie's whole frames.
  const std::vector<RayRecord>& keepWhole(int k, std::vector<RayRecord> records, double rays,
                                          double held);

  /// Keeps frame k's pictures until storedPictures() hands them out, those of the frames traced
  /// earliest let go beyond a quarter of the memory a read may take (their frames are then made
  /// from their records at their turn, read back from the store).
  void keepPictures(int k, std::vector<std::string> bytes);
  /// The bytes of one whole frame's records, and of the whole frames kept now.
  double frameBytes() const;
  double wholeBytes() const;

  /// Lets go of the least recently used whole frames, but not of `inUse`: those stored until the
  /// frames kept fit in MovieSettings::keptFrameBytes (a movie's keys at 1920×1080 would not fit
  /// in memory together), those not stored (no store: they are traced again if needed again)
  /// until they fit in MovieSettings::unstoredFrameBytes, the keys of interpolated frames last.
  /// Called where no reference to a kept frame is held.
  void keepWholeWithinBudget(const std::set<int>& inUse);
  /// Once the keys are made, the keys that the plan's interpolated frames are made between; none
  /// before.
  std::set<int> keysOfInterpolated() const;

  /// Records of a subset that was traced before: in memory, or in the store.
  std::optional<std::vector<RayRecord>> known(int k, const SceneDescription& subset,
                                              const std::vector<std::pair<int, int>>& pixels);

  /// `pixels` traced by `tracer` and stored as `subset` (a subset frame of their frame's scene):
  /// the tracer's count of rays, not the records' (these leave out the edge neighbours it traces
  /// and drops, FrameTracer::raysIntegrated), counted as the movie's.
  TracedPixels tracedSubset(const FrameTracer& tracer,
                            const std::vector<std::pair<int, int>>& pixels,
                            const SceneDescription& subset, CentreRays* kept = nullptr,
                            const std::vector<JacobianSample>& border = {});

  /// The re-traced pixels of interpolated frame k: known ones read, else traced (and stored).
  /// With `storeOnly`, a subset not known is NotServed, and nothing is counted or kept.
  PixelTracer retracedPixels(int k, const std::function<const FrameTracer&()>& tracer,
                             MovieFrameReport& report, bool storeOnly);

  /// The converged records of whole frame k's probes `probes` (settingsProbes of its records):
  /// traced with the converged rendering, or read where they were traced before, and stored as a
  /// subset of the frame's scene at that rendering. With `storeOnly`, probes not known are
  /// NotServed.
  std::vector<RayRecord> convergedProbes(int k, const std::vector<std::int32_t>& probes,
                                         bool storeOnly, int side = kConvergedSide);

  /// Whole frame k's own error against its converged picture: its probes (settingsProbes) against
  /// their converged records (convergedProbes). With `storeOnly`, probes not known are NotServed.
  const SettingsError& settingsOf(int k, bool storeOnly);

  /// Whole frame k's own error against its converged picture at the rendering of `lowered` (the
  /// same frame at another adaptive cap): its probes anti-aliased again from the frame's records
  /// (FrameTracer::antialiasAgain; read where that was done before, else done and stored as a
  /// subset of `lowered`'s scene) against their converged records.
  SettingsError settingsAt(int k, const MovieFrame& lowered);

  /// The re-traced pixels of the chain sources between frame k's inner keys among `keys` (read
  /// from the store once; those between other keys let go).
  std::vector<std::shared_ptr<const PathSamples>> samplesFor(int k, const std::vector<int>& keys);

  /// Frame k interpolated between `keys` (the nearest of them around it), completed to the target
  /// with the pixels `retrace` gives, held to the converged picture through the inner keys' own
  /// errors (settingsOf, with `storeOnly`). Where `chained` is given, each pixel's chain runs
  /// through samplesFor(k, keys) too, and *chained says whether there were any.
  PathCompletion interpolatedWith(int k, const std::vector<int>& keys, const PixelTracer& retrace,
                                  std::vector<RayRecord>& records, bool storeOnly,
                                  SettingsError& settings, bool* chained = nullptr);

  /// Frame k interpolated between `keys` (the nearest of the plan's keys), completed to the target.
  std::vector<RayRecord> interpolated(int k, const std::vector<int>& keys, MovieFrameReport& report,
                                      bool storeOnly);

  /// Records in the store that frame k was made between the keys of `keys` around it, unless it
  /// was recorded so before; nothing without a store, or with a key it did not store.
  /// `chained`: made through the chain sources' pixels (the chained recipe).
  void recordKeys(int k, const std::vector<int>& keys, bool chained);

  /// The store's id of whole frame k, if it is stored.
  std::optional<std::int64_t> storedId(int k) const;

  /// What frame k's pictures are of, where the store holds it: the frame stored whole, or the
  /// frame recorded as interpolated between stored keys by this movie's recipe.
  std::optional<PictureOrigin> pictureOrigin(int k) const;

  /// Whole frame k interpolated between the whole frames `wholeFrames` around it (k not among
  /// them) and completed to the target from its own records: the share the target needed there,
  /// and the rays re-tracing those pixels would have taken, nothing traced or stored.
  ShareMeasurement measuredShare(int k, const std::vector<int>& wholeFrames);
};
}

#endif
