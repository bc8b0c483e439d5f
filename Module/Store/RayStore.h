// Accumulation of traced frames in PostgreSQL: scenes, frames and their rays, written in one
// transaction each with binary COPY and read back bit-exact.
//
// Layout (schema version 3, chosen by measurement: bench/REPORT.md, "store layouts"; versions 5
// and 7 each added a word to the record). A ray is a packed record of kRecordBytes bytes, its
// fields as big-endian 32/64-bit words in the column order of the view rays_v (big-endian so that
// SQL can decode them with bit(n) casts). Rows of ray_blocks hold kBlockSize consecutive records in
// one bytea kept inline (STORAGE PLAIN: one row fills one 8 kB page, so nothing goes through
// TOAST). ray_blocks is partitioned by (frame, tile): each tile's rows go into a table of their
// own, created in the transaction that writes them, loaded with COPY FREEZE and attached to
// ray_blocks before the commit. A table created in the writing transaction is what lets PostgreSQL
// skip the WAL under wal_level = minimal (the embedded server's setting) and fsync the table at
// commit instead, writing the rays once rather than twice; with wal_level replica or logical (a
// server with replication) the same statements are WAL-logged as usual. Either way the commit is
// durable. SQL sees one row per ray through the view rays_v, which decodes the words; a predicate
// given to readFrame is evaluated there, on the server, and only the selected rays travel.
//
// Predicates (schema version 4): they are evaluated with the rights of the role asrt_predicate
// (kPredicateRole) alone, whatever the rights of the role that connected: it may read the views
// rays_v and path_points_v, and nothing else (no other table, no file, no signal to another
// backend). The migration creates it (which needs a superuser or CREATEROLE) and gives it a
// SECURITY DEFINER function, asrt_selected_rays, that evaluates the predicate as dynamic SQL:
// inside such a function PostgreSQL refuses to change "role" or "session_authorization", so a
// predicate cannot take back the caller's rights. Roles belong to the whole server: every ASRT
// database of a server shares this one. No role can be kept from the system catalogs and
// information functions, though, so a predicate is also held to a grammar of its own
// (RayPredicate.h: the ray's columns, constants, arithmetic, comparisons and pure math
// functions), checked by readFrame before anything is sent and, token by token, by the function
// again (schema version 6).
//
// Tiled frames: several processes (ranks) write the tiles of one frame concurrently,
// each tile in a transaction of its own. The frame row exists, committed, from beginTiledFrame()
// on, with status 'writing'; the transaction of the tile that brings the count of written tiles
// to the frame's tile count also makes it 'complete'. Everything that reads frames (listFrames,
// findFrame, readFrame, rays_v, path_points_v) shows complete frames only, so a frame whose
// writer died is never seen half-written; abandonedFrames() finds such frames for deleteFrame().
//
// Paths: a frame may also keep the polylines of some of its rays (RayPath, one per pixel), in
// ray_paths, written in the frame's transaction; the view path_points_v shows one row per point.
//
// Rendering (schema version 5): each record also keeps how many rays its pixel's colour comes from
// (RayRecord::raysPerPixel, rays_v's rays_per_pixel), and every frame's scene text has a
// "rendering" section. Migration 5 gave the frames stored before, all traced one ray a pixel,
// raysPerPixel = 1 and the section of singleRayRendering(), their scene rows and hashes following,
// so that such a frame is found (findFrame, writeFrame's duplicate check) by its description with
// that rendering.
//
// Traced rays and the grid (schema version 7): each record also says whether its centre ray was
// traced or interpolated by the adaptive grid (RayRecord::traced, rays_v's boolean traced), a
// word of its own after dvdj (268-byte records, still 30 to a row); and a frame's rendering
// section always names its lattice ("gridLattice"), since a text without one reads as the
// default grid. Migration 7 gave the records stored before, all traced, traced = true, and their
// texts "gridLattice": 1, their scene rows and hashes following as in migration 5. (Builds that
// traced on the grid before schema 7 stored its interpolated records unmarked: those read back as
// traced.)
//
// Plain C++: no VTK types, no libpq types in this header.
#ifndef asrt_RayStore_h
#define asrt_RayStore_h

#include "RayRecord.h"
#include "RecordAllocation.h"
#include "SceneDescription.h"
#include "asrtStoreModule.h"

#include <chrono>
#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace asrt
{
/// Every failure of the store: the message says what failed (connecting, schema version, a
/// duplicate frame, the server's error with its SQLSTATE, ...).
class ASRTSTORE_EXPORT StoreError : public std::runtime_error
{
public:
  explicit StoreError(const std::string& what, std::string sqlState = std::string())
    : std::runtime_error(what)
    , State(std::move(sqlState))
  {
  }
  /// The server's SQLSTATE when the server reported the error ("23505", ...), else empty.
  const std::string& sqlState() const { return this->State; }

private:
  std::string State;
};

/// The parameters that vary between the frames of one scene (e.g. along a movie). Together with
/// the rest of the scene they identify a frame.
struct FrameKey
{
  SpacetimeParameters spacetime;
  Vec3 cameraPosition = Vec3::Zero();
  Vec3 focalPoint = Vec3::Zero();
  Vec3 viewUp = Vec3::Zero();
  double viewAngle = 0;
  int width = 0, height = 0;
  std::string method;
  double step = 0;
  double relativeTolerance = 0, absoluteTolerance = 0;
};

struct FrameInfo
{
  std::int64_t id = 0;
  std::int64_t sceneId = 0;
  std::string sceneHash; ///< SHA-256 (hex) of the scene without its varying parameters
  std::string frameHash; ///< SHA-256 (hex) of effectiveSceneText(): the frame's identity
  std::string name;      ///< the scene's name
  std::string label;
  FrameKey key;
  std::string status; ///< "complete" (a frame being written is visible to nobody else)
  double writeSeconds = 0;
  double traceSeconds = 0; ///< NaN when the writer did not say
  std::string createdAt;   ///< ISO 8601, UTC
  std::int64_t rayCount = 0;
  int tileCount = 1;          ///< tiles it was written in (writeFrame: one per connection)
  std::int64_t pathCount = 0; ///< polylines stored with it (RayPath)
};

/// Refuses, with a StoreError naming the frame and the field, a frame row from which a read
/// cannot size its buffers (a row edited by hand, or a damaged database): frames.width or
/// frames.height below 1, more than kMaxFramePixels pixels in all (the tracer's own limit), or
/// frames.ray_count outside [0, kMaxFramePixels] (the most rays a frame may trace).
ASRTSTORE_EXPORT void checkFrameSize(std::int64_t id, int width, int height, std::int64_t rayCount);
inline void checkFrameSize(const FrameInfo& f)
{
  checkFrameSize(f.id, f.key.width, f.key.height, f.rayCount);
}

/// How writeFrame() stores a frame, besides its scene, label and records.
struct FrameWriteOptions
{
  /// Storing the same scene with the same parameters again throws a StoreError ("duplicate
  /// frame") unless `replace`, which replaces the old frame in the same transaction.
  bool replace = false;
  /// How long tracing the frame took, stored with it; NaN when the writer does not say.
  double traceSeconds = std::numeric_limits<double>::quiet_NaN();
  /// For the streaming writeFrame() of a producer that traces as the write goes: asked, once the
  /// last record is produced, how long tracing took, instead of traceSeconds.
  std::function<double()> tracedSeconds;
  /// The paths of some of its rays, stored in the same transaction (bit-exact, in the given
  /// order). At most one path per pixel, each pixel inside the frame's resolution: anything else
  /// is refused (StoreError) before touching the database.
  std::vector<RayPath> paths;
  /// For the streaming writeFrame(): `next` may be called from several threads at once (see
  /// there). The writeFrame() of records in memory always allows it.
  bool concurrentProducer = false;
  /// Asked again and again (from a thread of its own) while the frame is written: once it returns
  /// true, the statement under way is cancelled on the server (a wait for a lock or a slow server
  /// included) and the write is rolled back, throwing StoreError "writing the frame was
  /// cancelled" (SQLSTATE 57014). Once the commit has begun it is no longer asked: the frame is
  /// then stored. Empty: never cancelled.
  std::function<bool()> cancelled;

  FrameWriteOptions& replacing(bool r = true)
  {
    this->replace = r;
    return *this;
  }
  FrameWriteOptions& tracedIn(double seconds)
  {
    this->traceSeconds = seconds;
    return *this;
  }
  FrameWriteOptions& withPaths(std::vector<RayPath> p)
  {
    this->paths = std::move(p);
    return *this;
  }
  FrameWriteOptions& fromConcurrentProducer(bool c = true)
  {
    this->concurrentProducer = c;
    return *this;
  }
  FrameWriteOptions& tracedSecondsWhenDone(std::function<double()> seconds)
  {
    this->tracedSeconds = std::move(seconds);
    return *this;
  }
  FrameWriteOptions& cancelledWhen(std::function<bool()> c)
  {
    this->cancelled = std::move(c);
    return *this;
  }
};

/// An encoded picture of a frame (a PNG, a VTI), stored with what the movie that made it reported
/// of the frame, so that making the movie again writes its files without making the frame again.
struct FramePicture
{
  std::string format; ///< the encoding and its version, e.g. "png.1": [a-z0-9.], 1 to 32
  std::string bytes;
  int method = 0; ///< how the frame was made, as its maker numbers ways (0 to 255)
  double estimatedPsnr = std::numeric_limits<double>::infinity();
  double settingsPsnr = std::numeric_limits<double>::infinity();
  double shareRetraced = 0; ///< in [0, 1]
  double rays = 0;          ///< the rays its records hold, >= 0
};

/// How RayStore::storePicture's refusals of a picture whose origin is not (or no longer) stored
/// begin.
constexpr const char* kPictureRefused = "storing a picture: ";

/// What a picture is a picture of: a whole stored frame, or a frame not stored whole that was
/// interpolated by `recipe` between the stored frames `keys` (RayStore::recordInterpolatedFrame).
struct PictureOrigin
{
  std::optional<std::int64_t> wholeFrame;
  SceneDescription scene;
  std::string recipe;
  std::vector<std::int64_t> keys;
};

class ASRTSTORE_EXPORT RayStore
{
public:
  /// The schema version this build creates and understands.
  static constexpr int kSchemaVersion = 9;
  /// The role that evaluates readFrame()'s predicates (see the top of this file).
  static constexpr const char* kPredicateRole = "asrt_predicate";
  /// Bytes of one packed ray record (the fields of rays_v, big-endian; 260 before version 5, 264
  /// before version 7).
  static constexpr int kRecordBytes = 268;
  /// Rays per stored row of ray_blocks: as many as fit, inline, in one 8 kB heap page (31 of the
  /// 260-byte records before version 5; 30 of the 264- and 268-byte ones).
  static constexpr int kBlockSize = 30;
  /// A parallel write gives each connection at least this many rays (smaller frames are written
  /// over one: another connection's table and commit would cost more than they save).
  static constexpr std::size_t kParallelMinRays = 65536;
  /// Two: on two cores, the server's two backends take the write's CPU time in parallel (one
  /// backend alone is the bottleneck of a write; bench/REPORT.md, "store").
  static constexpr int kDefaultWriteConnections = 2;

  /// Connects. `conninfo` is a libpq connection string or URI; empty means libpq's defaults and
  /// the PG* environment variables. A connect_timeout of 10 s applies unless the conninfo or
  /// PGCONNECT_TIMEOUT sets one. Throws StoreError with libpq's reason (no server, wrong
  /// credentials, ...).
  explicit RayStore(const std::string& conninfo);
  ~RayStore();
  RayStore(const RayStore&) = delete;
  RayStore& operator=(const RayStore&) = delete;

  /// Creates or upgrades the schema in one transaction (serialised against concurrent migrators).
  /// Refuses a database whose schema is newer than this build's. Idempotent. Also drops the
  /// tables of rays left behind by frames deleted with plain SQL. `targetVersion` below
  /// kSchemaVersion stops at that version (to test migrations); it never downgrades.
  void migrate(int targetVersion = kSchemaVersion);
  /// migrate() for readers: brings an existing ASRT schema to the current version, but creates
  /// none. A database with no ASRT schema (version 0) is refused (StoreError "the database holds
  /// no ASRT schema ...") and left as it was.
  void upgrade();
  /// The database's schema version; 0 if it has none yet.
  int schemaVersion();

  /// Stores a frame in one transaction. Its identity is effectiveSceneText(scene): storing the
  /// same scene with the same parameters again is a duplicate (see FrameWriteOptions::replace).
  /// Labels and names must be valid UTF-8 without NUL bytes (anything else is refused before
  /// touching the database); they are bound as parameters, never spliced into SQL. Returns the
  /// frame's id. Of two writers of one frame at the same time, the one that commits first stands;
  /// the other throws StoreError: "duplicate frame" without `replace`, "frame not stored: another
  /// writer stored this scene ..." with it.
  std::int64_t writeFrame(const SceneDescription& scene, const std::string& label,
                          const std::vector<RayRecord>& records,
                          const FrameWriteOptions& options = FrameWriteOptions());
  /// As above, with the records produced one at a time by `next(index, record)` for index in
  /// [0, count), e.g. straight from a tracer. If it throws, the transaction is rolled back (no
  /// trace of the frame remains) and the exception propagates.
  ///
  /// With options.concurrentProducer (the overload above sets it: its records are in memory),
  /// `next` may be called from several threads at once, for different indices (each thread in
  /// increasing order), and a frame of at least 2 × kParallelMinRays rays is written over up to
  /// writeConnections() connections at once, as that many tiles of consecutive rays (FrameInfo's
  /// tileCount). It is still one frame, made visible by one commit: the other connections load
  /// their tiles into tables that nothing shows until the main transaction attaches them just
  /// before it commits; if anything fails, those tables are dropped (by this call, or by the next
  /// migrate() if this process dies). Without it, `next` is called in index order from the
  /// calling thread, and the frame is one tile.
  std::int64_t writeFrame(const SceneDescription& scene, const std::string& label,
                          std::size_t count,
                          const std::function<void(std::size_t, RayRecord&)>& next,
                          const FrameWriteOptions& options = FrameWriteOptions());

  /// Throws the StoreError that writeFrame() of `scene` with `replace` would throw, as the
  /// database stands, for the frame's identity: a complete frame of it stored and no `replace`, or
  /// a tiled frame of it being written. Writes nothing: a caller checks before computing the
  /// frame. The check is writeFrame()'s own (the same identity, the same refusals and messages);
  /// writeFrame() still makes it again in its transaction, since another writer may store the
  /// frame in between.
  void checkFrameIdentity(const SceneDescription& scene, bool replace);

  /// Connections a parallel write uses at most (see writeFrame); default kDefaultWriteConnections.
  /// 1 writes every frame over this store's own connection. The others are opened when first
  /// needed and kept; if the server refuses some (max_connections), a write uses those it got.
  void setWriteConnections(int n);
  int writeConnections() const;

  /// Starts (or joins) a frame written as `tileCount` tiles by writeTile(), possibly from several
  /// processes at once: the frame row is created and committed with status 'writing'. Every rank
  /// may call this with the same arguments; concurrent and later calls return the id of the same
  /// 'writing' frame as long as it is not complete (a different tile count is an error). A
  /// complete frame of the same identity is a duplicate (StoreError "duplicate frame") unless
  /// `replace`, which deletes it and starts a new one; `replace` never touches a 'writing' frame,
  /// since that is how the ranks of one write find each other (delete an abandoned one first).
  std::int64_t beginTiledFrame(const SceneDescription& scene, const std::string& label,
                               int tileCount, bool replace = false);
  /// Writes tile `tile` (0 <= tile < tileCount) of a frame begun by beginTiledFrame(), in one
  /// transaction; the transaction that writes the last missing tile also completes the frame.
  /// readFrame() returns the tiles in tile order, each in the order written. Writing a tile that
  /// is already written (or being written) throws a StoreError ("already written"). Tiles may be
  /// empty.
  void writeTile(std::int64_t frameId, int tile, const std::vector<RayRecord>& records);
  /// As above, with the records produced one at a time (see the streaming writeFrame()).
  void writeTile(std::int64_t frameId, int tile, std::size_t count,
                 const std::function<void(std::size_t, RayRecord&)>& next);
  /// Frames still 'writing' whose last tile (or, with none, whose start) is older than
  /// `olderThan`: most likely their writers died. Choose `olderThan` longer than the longest tile
  /// write, since a tile only counts once committed. deleteFrame() removes them.
  std::vector<std::int64_t> abandonedFrames(std::chrono::seconds olderThan);

  /// Complete frames, by id.
  std::vector<FrameInfo> listFrames();
  /// Throws StoreError if there is no complete frame `id`.
  FrameInfo frameInfo(std::int64_t id);
  /// The records of frame `id` in the order written (a tiled frame's tiles in tile order),
  /// bit-exact. `predicate`, if not empty, is a boolean expression over the columns of the view
  /// rays_v (e.g. "object_id = 2 AND image_order = 1") in the grammar of RayPredicate.h. It is
  /// the one piece of caller text that becomes SQL, deliberately: anything outside the grammar
  /// (a subquery, another name or function, a cast, a comment, ...) throws StoreError "the ray
  /// predicate was refused: " before anything is sent; what the grammar allows is sent token by
  /// token, checked again by the server's function, and evaluated there as the role
  /// kPredicateRole (which reads the rays views and nothing else), in a READ ONLY transaction
  /// that is rolled back, with predicateTimeout as statement_timeout, restricted to the frame's
  /// rays; only the selected records are sent back. A predicate that fails on the server (a
  /// division by zero, a string that is no number) throws StoreError "the ray predicate failed: "
  /// with the first line of the server's message, cut short. Refused (StoreError, before the
  /// predicate runs) when the role or its function is not set up safely: missing, granted more
  /// than the views, or a function that does not check the tokens (migrate() sets up again what
  /// it can).
  /// A frame whose row fails checkFrameSize(), or whose whole read would take more than the
  /// memory limit (setMemoryLimit), is refused (StoreError) before anything is allocated.
  std::vector<RayRecord> readFrame(std::int64_t id, const std::string& predicate = std::string());
  /// The paths stored with frame `id`, in the order written, bit-exact (empty if none).
  std::vector<RayPath> readPaths(std::int64_t id);
  /// Deletes a frame with its rays and paths, complete or not (e.g. abandoned), and its scene row
  /// if no other frame uses it; throws StoreError if there is none. It waits for reads of other
  /// frames that are under way (dropping a frame's tables locks ray_blocks briefly).
  void deleteFrame(std::int64_t id);
  /// The effective scene text of frame `id` (what effectiveSceneText() gave when it was written):
  /// enough to describe, re-trace or interpolate the frame. Throws StoreError if there is none.
  std::string frameSceneText(std::int64_t id);
  /// The complete frame stored for this scene with these parameters, if any.
  std::optional<std::int64_t> findFrame(const SceneDescription& scene);
  /// Records that the frame of `scene` (the scene at its parameters, not stored whole) was
  /// interpolated by `recipe` (a non-empty text naming how: its quality target, what it is held
  /// to) between the complete stored frames `keys`, in order (1 to 16); replaces an earlier record
  /// of the same frame and recipe. Throws StoreError naming what is wrong: an empty recipe, a key
  /// count outside 1..16, or a key that is no complete frame.
  void recordInterpolatedFrame(const SceneDescription& scene, const std::string& recipe,
                               const std::vector<std::int64_t>& keys);
  /// The keys recorded for the frame of `scene` and `recipe`, if any (they may have been deleted
  /// since).
  std::optional<std::vector<std::int64_t>> interpolatedFrameKeys(const SceneDescription& scene,
                                                                 const std::string& recipe);
  /// Whether the store holds a complete frame of some of the pixels of `scene` (the scene at its
  /// parameters, with a "subset" naming the pixels; at any rendering): what a frame between keys
  /// re-traced, or the probes a whole frame's own error was measured with. Where none is, nothing
  /// of the frame was traced before.
  bool hasSubsetFrames(const SceneDescription& scene);
  /// The records of the complete frames of some of the pixels of `scene` (the scene at its
  /// parameters and at its rendering; a "subset" it names is left out), in one list ordered by
  /// pixel (row j, then column i): what the frames between keys re-traced of that frame. Where two
  /// such frames hold one pixel, the one stored first stands. Each frame is read as readFrame
  /// reads it (its size checked, the memory limit held).
  std::vector<RayRecord> readSubsetRecords(const SceneDescription& scene);

  /// Stores `picture` of `origin`, replacing one of the same origin and format. A whole frame's
  /// goes when the frame is deleted; an interpolated frame's serves only while its frame is
  /// recorded as made between exactly `origin.keys` (recordInterpolatedFrame) and each of them is
  /// a complete frame. Throws StoreError naming what is wrong: a format not of [a-z0-9.] (1 to 32),
  /// a method outside 0..255, a share outside [0, 1], negative or NaN rays, a whole frame that is
  /// not stored complete, or an interpolated frame not recorded between those keys.
  void storePicture(const PictureOrigin& origin, const FramePicture& picture);
  /// The picture of `origin` in `format` stored before, if it still serves (see storePicture).
  std::optional<FramePicture> readPicture(const PictureOrigin& origin, const std::string& format);

  /// The reads are upgrade(), schemaVersion(), listFrames(), frameInfo(), frameSceneText(),
  /// findFrame(), interpolatedFrameKeys(), readPicture(), checkFrameIdentity(), abandonedFrames(),
  /// readFrame() and readPaths(). How long each statement of a read waits for a lock that another
  /// session holds (LOCK TABLE, a migration under way, ...) before the read gives up: StoreError
  /// "<what failed>: the frames table is locked by another session; gave up after 30 s" (SQLSTATE
  /// 55P03). Zero: reads wait as long as a lock is held. Default kDefaultReadLockTimeout. Writes
  /// wait for locks as long as it takes (FrameWriteOptions::cancelled stops them); the tidying up
  /// after others' failed or deleted writes that reads do in passing gives way to a lock at once
  /// and is left for later.
  static constexpr std::chrono::milliseconds kDefaultReadLockTimeout{ 30000 };
  /// Throws StoreError for a negative timeout or one beyond PostgreSQL's (about 24 days).
  void setReadLockTimeout(std::chrono::milliseconds t);
  /// Asked again and again (from a thread of its own) while a read runs: once it returns true, the
  /// read's statement under way is cancelled on the server (a wait for a lock included) and the
  /// read throws StoreError "reading from the store was cancelled" (SQLSTATE 57014); while it
  /// stays true, no read starts. Empty (default): never.
  void setReadCancellation(std::function<bool()> cancelled);

  void setPredicateTimeout(std::chrono::milliseconds t) { this->PredicateTimeout = t; }
  /// The bytes that readFrame() may allocate for the records of a whole frame; 0 (default):
  /// defaultMemoryLimit(). A frame that would need more is refused (StoreError) before anything
  /// is allocated.
  void setMemoryLimit(double bytes) { this->MemoryLimit = bytes; }
  /// The server process of this connection (for tests that break it).
  int backendPid() const;

private:
  struct Impl;
  Impl* P;
  std::chrono::milliseconds PredicateTimeout{ 60000 };
  double MemoryLimit = 0;
};
}

#endif
