// The public methods of RayStore. The work is shared out: StoreRecordCodec (the packed record),
// StoreSchema and StoreSchemaHistory (versions and migrations), PgSession (libpq), StoreFrameRows
// and StoreTileRows (the rows of frames and of their rays), StoreFanOut (helper connections).
#include "RayStore.h"

#include "PgSession.h"
#include "RayPredicate.h"
#include "StoreCancellation.h"
#include "StoreFanOut.h"
#include "StoreFrameRows.h"
#include "StorePictures.h"
#include "StoreReadLimits.h"
#include "StoreRecordCodec.h"
#include "StoreSchema.h"
#include "StoreTileRows.h"

#include <algorithm>
#include <climits>
#include <iterator>
#include <utility>

namespace asrt
{
using storage::RecordProducer;

namespace
{
/// A write retries after its scene row vanished under a concurrent deletion of the scene's last
/// frame (SceneVanished); losing that race five times in a row means frames of the scene are
/// deleted as fast as they are written, and the caller should hear so.
constexpr int FrameWriteAttempts = 5;
/// Every rank of a tiled frame calls beginTiledFrame() at about the same time, and a concurrent
/// replacement or deletion can take the frame's row away between their statements: twice the
/// attempts of a plain write, since the ranks race each other as well.
constexpr int TiledFrameBeginAttempts = 10;

/// The boundaries of `tiles` tiles of consecutive rays among `count`: whole rows of kBlockSize
/// rays in every tile but the last.
std::vector<std::size_t> tileBounds(std::size_t count, std::size_t tiles)
{
  std::vector<std::size_t> bounds;
  for (std::size_t k = 0; k < tiles; ++k)
  {
    bounds.push_back(count * k / tiles / RayStore::kBlockSize * RayStore::kBlockSize);
  }
  bounds.push_back(count);
  return bounds;
}

/// The tiles shared out between `groups` connections by their rays: each group's tile numbers,
/// comma-separated.
std::vector<std::string> groupTiles(const std::vector<storage::TileRays>& tiles, std::size_t groups)
{
  std::vector<std::string> out(groups);
  std::vector<std::int64_t> load(groups, 0);
  for (const storage::TileRays& t : tiles)
  {
    const std::size_t g = std::size_t(std::min_element(load.begin(), load.end()) - load.begin());
    out[g] += (out[g].empty() ? "" : ",") + std::to_string(t.tile);
    load[g] += t.count;
  }
  return out;
}

/// The name of a snapshot this transaction exports for the helpers of a read.
std::string exportSnapshot(PGconn* conn)
{
  pg::Result r = pg::exec(conn, "SELECT pg_export_snapshot()", "reading the rays failed");
  std::string snapshot = pg::getText(r.get(), 0, 0);
  // The server's name for it; checked all the same before it goes into SQL.
  if (snapshot.empty() ||
      snapshot.find_first_not_of("0123456789ABCDEFabcdef-") != std::string::npos)
  {
    throw StoreError("reading the rays failed: unexpected snapshot name \"" + snapshot + "\"");
  }
  return snapshot;
}

/// A predicate's failure as the user reads it: the first line of the server's message (its
/// CONTEXT would repeat the predicate inside the function's SQL), at most PredicateErrorBytes
/// long, cut at a character boundary.
constexpr std::size_t PredicateErrorBytes = 240;
StoreError predicateFailure(const StoreError& e)
{
  std::string line = e.what();
  line = line.substr(0, line.find('\n'));
  if (line.size() > PredicateErrorBytes)
  {
    std::size_t cut = PredicateErrorBytes;
    while (cut > 0 && (static_cast<unsigned char>(line[cut]) & 0xC0) == 0x80)
    {
      --cut;
    }
    line = line.substr(0, cut) + "...";
  }
  return StoreError(line, e.sqlState());
}

/// The rays of complete frame `id` that satisfy `predicate`, in ray order (see readFrame).
std::vector<RayRecord> readSelectedRays(PGconn* conn, std::int64_t id, std::int64_t rayCount,
                                        const std::string& predicate,
                                        std::chrono::milliseconds timeout)
{
  if (const std::optional<std::string> problem = storage::predicateRoleProblem(conn))
  {
    throw StoreError("the ray predicate was not evaluated: " + *problem);
  }
  pg::Params()
    .text(std::to_string(timeout.count()) + "ms")
    .exec(conn, "SELECT set_config('statement_timeout', $1, true)",
          "setting the predicate's time limit failed");
  // The predicate is bound as a parameter here; asrt_selected_rays makes it SQL, evaluated with
  // the rights of the predicate role alone (StoreSchemaHistory.h, SchemaV4). The server sends
  // the selected records only, in any order.
  std::vector<std::pair<std::int64_t, RayRecord>> selected;
  try
  {
    pg::Params().i64(id).text(predicate).stream(
      conn, "SELECT ray, record_bytes FROM asrt_selected_rays($1, $2)", "the ray predicate failed",
      [&](const PGresult* row)
      {
        const std::int64_t ray = pg::getI64(row, 0, 0);
        if (PQgetisnull(row, 0, 0) || ray < 0 || ray >= rayCount ||
            PQgetlength(row, 0, 1) != RayStore::kRecordBytes)
        {
          throw StoreError("the ray predicate failed: its query gave a row that is no ray of "
                           "frame " +
                           std::to_string(id));
        }
        selected.emplace_back(ray, RayRecord());
        storage::decodeRecords(PQgetvalue(row, 0, 1), 1, &selected.back().second);
      });
  }
  catch (const StoreError& e)
  {
    throw predicateFailure(e);
  }
  std::sort(selected.begin(), selected.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<RayRecord> records;
  records.reserve(selected.size());
  for (std::size_t k = 0; k < selected.size(); ++k)
  {
    if (k > 0 && selected[k].first == selected[k - 1].first)
    {
      throw StoreError("the ray predicate failed: its query gave ray " +
                       std::to_string(selected[k].first) + " twice");
    }
    records.push_back(selected[k].second);
  }
  return records;
}
}

struct RayStore::Impl
{
  explicit Impl(const std::string& conninfo)
    : Conn(pg::connect(conninfo))
    , Helpers(conninfo)
  {
  }
  pg::Connection Conn;
  /// The other connections of a parallel write or read, opened when first needed.
  storage::HelperConnections Helpers;
  bool SchemaChecked = false;
  int WriteConnections = RayStore::kDefaultWriteConnections;
  storage::ReadLimits Limits{ RayStore::kDefaultReadLockTimeout, {} };

  PGconn* conn() const { return this->Conn.get(); }

  /// Reconnects once after the connection broke (server restart, terminated backend).
  void ensureConnected()
  {
    if (PQstatus(this->conn()) != CONNECTION_OK)
    {
      this->SchemaChecked = false;
      if (!pg::reconnect(this->conn()))
      {
        throw StoreError("lost the connection to PostgreSQL and could not reconnect: " +
                         pg::oneLine(PQerrorMessage(this->conn())));
      }
    }
  }

  /// The connection, reconnected if it broke (before a read's limits are put on it).
  PGconn* connected()
  {
    this->ensureConnected();
    return this->conn();
  }

  void requireSchema()
  {
    this->ensureConnected();
    if (!this->SchemaChecked)
    {
      storage::requireCurrentSchema(this->conn());
      this->SchemaChecked = true;
    }
  }

  /// Helper connections for sharing out `tiles` tiles (at most WriteConnections connections in
  /// all, the store's own included).
  std::vector<PGconn*> helpersFor(std::size_t tiles)
  {
    return this->Helpers.get(
      int(std::min<std::size_t>(std::size_t(this->WriteConnections), tiles)) - 1);
  }

  std::int64_t writeFrame(const SceneDescription& scene, const std::string& label,
                          std::size_t count, const RecordProducer& next,
                          const FrameWriteOptions& options, bool concurrentProducer);
  std::vector<RayRecord> readAllRays(std::int64_t id, std::int64_t rayCount);
};

namespace
{
/// What one writeFrame() call stores.
struct FrameToWrite
{
  const SceneDescription& scene;
  const std::string& label;
  const storage::SceneTexts& texts;
  std::size_t count;
  const RecordProducer& next;
  const FrameWriteOptions& options;
  std::chrono::steady_clock::time_point start; ///< write_seconds counts from it
};

/// One attempt (one scene row) at writing a frame, phase by phase, over the store's connection
/// and `helpers`.
class FrameWrite
{
public:
  FrameWrite(PGconn* conn, const FrameToWrite& frame, std::vector<PGconn*> helpers)
    : Conn(conn)
    , Frame(frame)
    , Helpers(std::move(helpers))
    , Bounds(tileBounds(frame.count, this->Helpers.size() + 1))
    , Tiles(int(this->Helpers.size()) + 1)
  {
  }

  /// The frame's transaction: its identity claimed, its row, its rays and paths, its completion.
  /// The options' cancellation is watched until the commit; the watch ends (its thread joined)
  /// before the transaction is rolled back, so that no cancel reaches the rollback.
  std::int64_t run(std::int64_t sceneId)
  {
    return pg::transaction(this->Conn, pg::WriteBegin,
                           [&]
                           {
                             std::vector<PGconn*> connections = this->Helpers;
                             connections.push_back(this->Conn);
                             storage::StatementCancellation cancel(this->Frame.options.cancelled,
                                                                   connections);
                             this->Cancel = &cancel;
                             try
                             {
                               return this->store(sceneId, cancel);
                             }
                             catch (...)
                             {
                               this->Cancel = nullptr;
                               cancel.check(); // the cancellation, not what it broke
                               throw;
                             }
                           });
  }

  /// Whether this attempt deleted a frame it replaces (whose tables are then orphans).
  bool replaced() const { return this->Replaced; }
  /// After a failure: drops what the helper connections committed for the frame (the main
  /// connection may be the one that broke).
  void dropHelpersTiles() const
  {
    if (this->WritingId >= 0)
    {
      storage::dropUnattachedTiles(PQstatus(this->Conn) == CONNECTION_OK ? this->Conn
                                                                         : this->Helpers.front(),
                                   this->WritingId);
    }
  }

private:
  std::int64_t store(std::int64_t sceneId, storage::StatementCancellation& cancel)
  {
    this->claimIdentity();
    const std::int64_t id = this->insertRow(sceneId);
    this->writeRays(id);
    cancel.check();
    storage::copyPaths(this->Conn, id, this->Frame.options.paths);
    for (int tile = 0; tile < this->Tiles; ++tile)
    {
      storage::recordTile(this->Conn, id, tile, this->tileCount(tile),
                          "recording the frame's rays failed");
    }
    this->complete(id);
    cancel.stop();
    cancel.check();
    this->Cancel = nullptr;
    pg::exec(this->Conn, "COMMIT", "committing the frame failed");
    return id;
  }

  /// The frame's records, stopping at a cancellation.
  void produce(std::size_t k, RayRecord& r) const
  {
    if (this->Cancel)
    {
      this->Cancel->check();
    }
    this->Frame.next(k, r);
  }

  std::int64_t tileCount(int tile) const
  {
    return std::int64_t(this->Bounds[std::size_t(tile) + 1] - this->Bounds[std::size_t(tile)]);
  }

  /// A complete frame of the same identity is a duplicate, or is replaced (checkFrameIdentity()
  /// makes the same check without the lock).
  void claimIdentity()
  {
    const std::optional<storage::FrameOfIdentity> old =
      storage::findFrameOfIdentity(this->Conn, this->Frame.texts, true);
    if (!old)
    {
      return;
    }
    storage::refuseIdentityClash(*old, this->Frame.options.replace);
    storage::deleteFrameRow(this->Conn, old->id, "deleting the frame to be replaced failed");
    this->Replaced = true;
  }

  std::int64_t insertRow(std::int64_t sceneId)
  {
    try
    {
      const std::int64_t id =
        *storage::insertFrame(this->Conn, sceneId, this->Frame.texts, this->Frame.scene,
                              this->Frame.label, this->Tiles, false);
      if (this->Tiles > 1)
      {
        this->WritingId = id;
      }
      return id;
    }
    catch (const StoreError& e)
    {
      if (e.sqlState() == "23505")
      {
        // Another writer stored the same frame between our check and our insert: that writer
        // committed first, so its frame stands, replace or not.
        throw StoreError(
          this->Frame.options.replace
            ? "frame not stored: another writer stored this scene with these parameters at the "
              "same time, after this write had looked for a frame to replace; that writer's "
              "frame stands (store again to replace it)"
            : "duplicate frame: this scene with these parameters was just stored by another "
              "writer; pass replace = true to replace it",
          e.sqlState());
      }
      throw;
    }
  }

  void writeRays(std::int64_t id)
  {
    if (this->Tiles == 1)
    {
      storage::copyTile(this->Conn, id, 0, this->Frame.count,
                        [this](std::size_t k, RayRecord& r) { this->produce(k, r); });
      return;
    }
    pg::Params().i64(id).exec(this->Conn, storage::writerLock("pg_advisory_xact_lock"),
                              "locking the frame failed");
    this->loadTilesInParallel(id);
    // Attached together at the end: ATTACH PARTITION locks ray_blocks against other writers'
    // attachments, so it waits for no COPY.
    for (int tile = 0; tile < this->Tiles; ++tile)
    {
      if (this->tileCount(tile) > 0)
      {
        pg::exec(this->Conn, storage::attachBlockTable("ray_blocks", id, tile),
                 "attaching the rays failed");
      }
    }
  }

  /// Tile 0 over the main connection, each other tile loaded and committed by a helper
  /// connection, not attached. Any failure stops the others.
  void loadTilesInParallel(std::int64_t id)
  {
    storage::FanOut fan(this->Helpers);
    const RecordProducer checked = [&fan, this](std::size_t k, RayRecord& r)
    {
      if (fan.failed())
      {
        throw storage::ShareStopped(
          "writing the rays failed: another connection of the write failed");
      }
      this->produce(k, r);
    };
    fan.run(
      [&](PGconn* conn, std::size_t k)
      {
        const auto tile = std::int32_t(k + 1);
        pg::exec(conn, pg::WriteBegin, "starting a transaction failed");
        storage::loadTile(conn, id, tile, this->Bounds[k + 1], std::size_t(this->tileCount(tile)),
                          checked);
        pg::exec(conn, "COMMIT", "committing the rays failed");
      },
      [&] { storage::loadTile(this->Conn, id, 0, 0, this->Bounds[1], checked); });
  }

  void complete(std::int64_t id)
  {
    const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - this->Frame.start).count();
    pg::Params()
      .i64(id)
      .i64(std::int64_t(this->Frame.count))
      .f64(seconds)
      .f64(this->Frame.options.tracedSeconds ? this->Frame.options.tracedSeconds()
                                             : this->Frame.options.traceSeconds)
      .exec(this->Conn,
            "UPDATE frames SET status = 'complete', ray_count = $2, write_seconds = $3, "
            "trace_seconds = nullif($4, 'NaN'), completed_at = clock_timestamp() WHERE id = $1",
            "completing the frame failed");
  }

  PGconn* Conn;
  const FrameToWrite& Frame;
  std::vector<PGconn*> Helpers;
  std::vector<std::size_t> Bounds;
  int Tiles;
  bool Replaced = false;
  std::int64_t WritingId = -1; ///< the frame of a parallel write, once it has an id
  const storage::StatementCancellation* Cancel = nullptr; ///< while the transaction's body runs
};
}

std::int64_t RayStore::Impl::writeFrame(const SceneDescription& scene, const std::string& label,
                                        std::size_t count, const RecordProducer& next,
                                        const FrameWriteOptions& options, bool concurrentProducer)
{
  const auto start = std::chrono::steady_clock::now();
  pg::requireText(label, "the label");
  pg::requireText(scene.name, "the scene name");
  const storage::SceneTexts texts = storage::sceneTexts(scene);
  storage::checkPaths(scene, options.paths);
  this->requireSchema();
  // A large frame from a producer that any thread may call goes in as several tiles, each over a
  // connection of its own: one backend alone is the bottleneck of a write (bench/REPORT.md).
  std::vector<PGconn*> helpers;
  if (concurrentProducer && count >= kParallelMinRays)
  {
    helpers = this->helpersFor(count / kParallelMinRays);
  }
  const FrameToWrite frame{ scene, label, texts, count, next, options, start };
  for (int attempt = 0;; ++attempt)
  {
    const std::int64_t sceneId = storage::sceneRow(this->conn(), texts);
    FrameWrite write(this->conn(), frame, helpers);
    try
    {
      const std::int64_t frameId = write.run(sceneId);
      if (write.replaced())
      {
        storage::dropOrphanBlocks(this->conn());
      }
      return frameId;
    }
    catch (const storage::SceneVanished&)
    {
      if (attempt == FrameWriteAttempts - 1)
      {
        throw StoreError("writing the frame failed: its scene row kept disappearing under "
                         "concurrent deletions");
      }
    }
    catch (...)
    {
      write.dropHelpersTiles();
      storage::dropUnusedScenes(this->conn(), sceneId);
      throw;
    }
  }
}

std::vector<RayRecord> RayStore::Impl::readAllRays(std::int64_t id, std::int64_t rayCount)
{
  PGconn* conn = this->conn();
  const std::vector<storage::TileRays> tiles = storage::readTileRays(conn, id, rayCount);
  // Tiles of a large frame are read over several connections at once, from one snapshot
  // (exported by this transaction), each decoded on a thread of its own; the tiles are shared
  // out by their rays.
  std::vector<PGconn*> helpers;
  if (tiles.size() > 1 && rayCount >= std::int64_t(2 * kParallelMinRays))
  {
    helpers = this->helpersFor(tiles.size());
  }
  std::vector<RayRecord> records = allocateRecords(std::size_t(rayCount));
  const std::vector<std::string> groups = groupTiles(tiles, helpers.size() + 1);
  const std::string snapshot = helpers.empty() ? std::string() : exportSnapshot(conn);
  // The helpers' statements are the read's too: limited and cancelled alike.
  std::optional<storage::ReadScope> helpersRead;
  if (!helpers.empty())
  {
    helpersRead.emplace(helpers, this->Limits);
  }
  std::vector<std::int64_t> gots(helpers.size() + 1, 0);
  storage::FanOut(helpers).run(
    [&](PGconn* c, std::size_t k)
    {
      pg::exec(c, pg::ReadBegin, "starting a transaction failed");
      pg::exec(c, "SET TRANSACTION SNAPSHOT '" + snapshot + "'", "reading the rays failed");
      gots[k + 1] = storage::readTileGroup(c, id, groups[k + 1], tiles, records);
      pg::exec(c, "ROLLBACK", "ending the read failed");
    },
    [&] { gots[0] = storage::readTileGroup(conn, id, groups[0], tiles, records); });
  std::int64_t got = 0;
  for (const std::int64_t n : gots)
  {
    got += n;
  }
  if (got != rayCount)
  {
    throw StoreError("frame " + std::to_string(id) + " is inconsistent: it says " +
                     std::to_string(rayCount) + " rays, its blocks hold " + std::to_string(got));
  }
  return records;
}

// -----------------------------------------------------------------------------------------------

RayStore::RayStore(const std::string& conninfo)
  : P(new Impl(conninfo))
{
}

RayStore::~RayStore()
{
  delete this->P;
}

int RayStore::backendPid() const
{
  return PQbackendPID(this->P->conn());
}

int RayStore::schemaVersion()
try
{
  const storage::ReadScope read({ this->P->connected() }, this->P->Limits);
  return storage::readSchemaVersion(this->P->conn());
}
catch (...)
{
  storage::rethrowReadFailure(this->P->Limits);
}

void RayStore::migrate(int targetVersion)
{
  if (targetVersion < 1 || targetVersion > kSchemaVersion)
  {
    throw StoreError("cannot migrate to schema version " + std::to_string(targetVersion) +
                     ": this build knows versions 1 to " + std::to_string(kSchemaVersion));
  }
  this->P->ensureConnected();
  this->P->SchemaChecked = false;
  storage::migrateSchema(this->P->conn(), targetVersion);
  if (targetVersion == kSchemaVersion)
  {
    storage::dropOrphanBlocks(this->P->conn());
    storage::dropUnusedScenes(this->P->conn(), -1);
  }
}

void RayStore::upgrade()
try
{
  const storage::ReadScope read({ this->P->connected() }, this->P->Limits);
  this->P->SchemaChecked = false;
  storage::migrateSchema(this->P->conn(), kSchemaVersion, false);
  read.tidyBriefly(
    [this]
    {
      storage::dropOrphanBlocks(this->P->conn());
      storage::dropUnusedScenes(this->P->conn(), -1);
    });
}
catch (...)
{
  storage::rethrowReadFailure(this->P->Limits);
}

void RayStore::setReadLockTimeout(std::chrono::milliseconds t)
{
  if (t.count() < 0 || t.count() > INT_MAX)
  {
    throw StoreError("a read's lock timeout must be between 0 and " + std::to_string(INT_MAX) +
                     " ms (got " + std::to_string(t.count()) + ")");
  }
  this->P->Limits.lockTimeout = t;
}

void RayStore::setReadCancellation(std::function<bool()> cancelled)
{
  this->P->Limits.cancelled = std::move(cancelled);
}

void RayStore::checkFrameIdentity(const SceneDescription& scene, bool replace)
try
{
  pg::requireText(scene.name, "the scene name");
  const storage::SceneTexts texts = storage::sceneTexts(scene);
  const storage::ReadScope read({ this->P->connected() }, this->P->Limits);
  this->P->requireSchema();
  PGconn* conn = this->P->conn();
  pg::transaction(conn, pg::ReadBegin,
                  [&]
                  {
                    if (const std::optional<storage::FrameOfIdentity> old =
                          storage::findFrameOfIdentity(conn, texts, false))
                    {
                      storage::refuseIdentityClash(*old, replace);
                    }
                    pg::exec(conn, "ROLLBACK", "ending the read failed");
                  });
}
catch (...)
{
  storage::rethrowReadFailure(this->P->Limits);
}

std::int64_t RayStore::writeFrame(const SceneDescription& scene, const std::string& label,
                                  const std::vector<RayRecord>& records,
                                  const FrameWriteOptions& options)
{
  return this->P->writeFrame(
    scene, label, records.size(), [&records](std::size_t k, RayRecord& r) { r = records[k]; },
    options, true);
}

std::int64_t RayStore::writeFrame(const SceneDescription& scene, const std::string& label,
                                  std::size_t count, const RecordProducer& next,
                                  const FrameWriteOptions& options)
{
  return this->P->writeFrame(scene, label, count, next, options, options.concurrentProducer);
}

void RayStore::setWriteConnections(int n)
{
  if (n < 1)
  {
    throw StoreError("a write needs at least one connection (got " + std::to_string(n) + ")");
  }
  this->P->WriteConnections = n;
}

int RayStore::writeConnections() const
{
  return this->P->WriteConnections;
}

std::int64_t RayStore::beginTiledFrame(const SceneDescription& scene, const std::string& label,
                                       int tileCount, bool replace)
{
  if (tileCount < 1)
  {
    throw StoreError("a tiled frame needs at least one tile (got " + std::to_string(tileCount) +
                     ")");
  }
  pg::requireText(label, "the label");
  pg::requireText(scene.name, "the scene name");
  const storage::SceneTexts texts = storage::sceneTexts(scene);
  this->P->requireSchema();
  PGconn* conn = this->P->conn();
  // Every rank runs this at about the same time. INSERT ... ON CONFLICT DO NOTHING waits for a
  // concurrent inserter of the same identity and then yields to it, so that all agree on its row.
  // The row can still vanish between that and the SELECT (a concurrent replace or delete), and so
  // can the scene's row before the frame's refers to it: then try again.
  for (int attempt = 0; attempt < TiledFrameBeginAttempts; ++attempt)
  {
    const std::int64_t sceneId = storage::sceneRow(conn, texts);
    storage::TiledFrameStart start;
    try
    {
      start =
        storage::beginOrJoinTiledFrame(conn, sceneId, texts, scene, label, tileCount, replace);
    }
    catch (const storage::SceneVanished&)
    {
      continue;
    }
    catch (...)
    {
      storage::dropUnusedScenes(conn, sceneId);
      throw;
    }
    if (start.replaced)
    {
      storage::dropOrphanBlocks(conn);
    }
    if (start.id)
    {
      return *start.id;
    }
  }
  throw StoreError("starting the tiled frame failed: its row kept disappearing under concurrent "
                   "replacements or deletions");
}

void RayStore::writeTile(std::int64_t frameId, int tile, const std::vector<RayRecord>& records)
{
  this->writeTile(frameId, tile, records.size(),
                  [&records](std::size_t k, RayRecord& r) { r = records[k]; });
}

void RayStore::writeTile(std::int64_t frameId, int tile, std::size_t count,
                         const RecordProducer& next)
{
  this->P->requireSchema();
  PGconn* conn = this->P->conn();
  const std::string which = "tile " + std::to_string(tile) + " of frame " + std::to_string(frameId);
  pg::transaction(
    conn, pg::WriteBegin,
    [&]
    {
      const int tileCount = storage::lockFrameForTile(conn, frameId, tile, which);
      try
      {
        storage::copyTile(conn, frameId, tile, count, next);
        storage::recordTile(conn, frameId, tile, std::int64_t(count), "recording the tile failed");
      }
      catch (const StoreError& e)
      {
        if (e.sqlState() == "23505" || e.sqlState() == "42P07")
        {
          // A concurrent writer of the same tile committed first (its row of frame_tiles, or its
          // table of rays, exists).
          throw StoreError("writing " + which + " failed: the tile is already written",
                           e.sqlState());
        }
        throw;
      }
      storage::completeIfLastTile(conn, frameId, tileCount);
      pg::exec(conn, "COMMIT", "committing the tile failed");
    });
}

std::vector<std::int64_t> RayStore::abandonedFrames(std::chrono::seconds olderThan)
try
{
  const storage::ReadScope read({ this->P->connected() }, this->P->Limits);
  this->P->requireSchema();
  pg::Result r =
    pg::Params()
      .i64(std::int64_t(olderThan.count()))
      .exec(this->P->conn(),
            "SELECT f.id FROM frames f WHERE f.status = 'writing' AND coalesce((SELECT "
            "max(t.written_at) FROM frame_tiles t WHERE t.frame_id = f.id), f.created_at) "
            "< clock_timestamp() - $1::float8 * interval '1 second' ORDER BY f.id",
            "looking for abandoned frames failed");
  std::vector<std::int64_t> ids;
  for (int row = 0; row < PQntuples(r.get()); ++row)
  {
    ids.push_back(pg::getI64(r.get(), row, 0));
  }
  return ids;
}
catch (...)
{
  storage::rethrowReadFailure(this->P->Limits);
}

std::vector<FrameInfo> RayStore::listFrames()
try
{
  const storage::ReadScope read({ this->P->connected() }, this->P->Limits);
  this->P->requireSchema();
  return storage::selectFrames(this->P->conn(), pg::Params(), " ORDER BY f.id",
                               "listing the frames failed");
}
catch (...)
{
  storage::rethrowReadFailure(this->P->Limits);
}

FrameInfo RayStore::frameInfo(std::int64_t id)
try
{
  const storage::ReadScope read({ this->P->connected() }, this->P->Limits);
  this->P->requireSchema();
  const std::vector<FrameInfo> frames = storage::selectFrames(
    this->P->conn(), pg::Params().i64(id), " AND f.id = $1", "reading the frame failed");
  if (frames.empty())
  {
    throw StoreError("there is no frame " + std::to_string(id));
  }
  return frames.front();
}
catch (...)
{
  storage::rethrowReadFailure(this->P->Limits);
}

std::string RayStore::frameSceneText(std::int64_t id)
try
{
  const storage::ReadScope read({ this->P->connected() }, this->P->Limits);
  this->P->requireSchema();
  pg::Result r = storage::completeFrameColumn(this->P->conn(), id, "effective_text",
                                              "reading the frame's scene failed");
  return pg::getText(r.get(), 0, 0);
}
catch (...)
{
  storage::rethrowReadFailure(this->P->Limits);
}

std::optional<std::int64_t> RayStore::findFrame(const SceneDescription& scene)
try
{
  const storage::SceneTexts texts = storage::sceneTexts(scene);
  const storage::ReadScope read({ this->P->connected() }, this->P->Limits);
  this->P->requireSchema();
  pg::Result r =
    pg::Params()
      .bytes(texts.frame)
      .exec(this->P->conn(),
            "SELECT id FROM frames WHERE frame_hash = sha256($1) AND status = 'complete'",
            "looking for the frame failed");
  if (PQntuples(r.get()) == 0)
  {
    return std::nullopt;
  }
  return pg::getI64(r.get(), 0, 0);
}
catch (...)
{
  storage::rethrowReadFailure(this->P->Limits);
}

void RayStore::recordInterpolatedFrame(const SceneDescription& scene, const std::string& recipe,
                                       const std::vector<std::int64_t>& keys)
{
  const storage::SceneTexts texts = storage::sceneTexts(scene);
  this->P->requireSchema();
  storage::recordInterpolatedKeys(this->P->conn(), texts, recipe, keys);
}

std::optional<std::vector<std::int64_t>> RayStore::interpolatedFrameKeys(
  const SceneDescription& scene, const std::string& recipe)
try
{
  const storage::SceneTexts texts = storage::sceneTexts(scene);
  const storage::ReadScope read({ this->P->connected() }, this->P->Limits);
  this->P->requireSchema();
  return storage::interpolatedKeys(this->P->conn(), texts, recipe);
}
catch (...)
{
  storage::rethrowReadFailure(this->P->Limits);
}

bool RayStore::hasSubsetFrames(const SceneDescription& scene)
try
{
  const storage::SceneTexts texts = storage::sceneTexts(scene);
  const storage::ReadScope read({ this->P->connected() }, this->P->Limits);
  this->P->requireSchema();
  return storage::subsetFramesExist(this->P->conn(), texts, scene);
}
catch (...)
{
  storage::rethrowReadFailure(this->P->Limits);
}

std::vector<RayRecord> RayStore::readSubsetRecords(const SceneDescription& scene)
{
  std::vector<std::int64_t> ids;
  try
  {
    const storage::SceneTexts texts = storage::sceneTexts(scene);
    const storage::ReadScope read({ this->P->connected() }, this->P->Limits);
    this->P->requireSchema();
    ids = storage::subsetFrameIds(this->P->conn(), texts, scene);
  }
  catch (...)
  {
    storage::rethrowReadFailure(this->P->Limits);
  }
  std::vector<RayRecord> records;
  for (std::int64_t id : ids)
  {
    std::vector<RayRecord> frame = this->readFrame(id);
    records.insert(records.end(), std::make_move_iterator(frame.begin()),
                   std::make_move_iterator(frame.end()));
  }
  // Ordered by pixel, the first stored of each pixel first (a stable sort keeps the frames'
  // order), then the later ones dropped.
  std::stable_sort(records.begin(), records.end(),
                   [](const RayRecord& a, const RayRecord& b)
                   { return a.j != b.j ? a.j < b.j : a.i < b.i; });
  records.erase(std::unique(records.begin(), records.end(),
                            [](const RayRecord& a, const RayRecord& b)
                            { return a.i == b.i && a.j == b.j; }),
                records.end());
  return records;
}

void RayStore::storePicture(const PictureOrigin& origin, const FramePicture& picture)
{
  const storage::SceneTexts texts =
    origin.wholeFrame ? storage::SceneTexts() : storage::sceneTexts(origin.scene);
  this->P->requireSchema();
  storage::upsertPicture(this->P->conn(), origin, texts, picture);
}

std::optional<FramePicture> RayStore::readPicture(const PictureOrigin& origin,
                                                  const std::string& format)
try
{
  const storage::SceneTexts texts =
    origin.wholeFrame ? storage::SceneTexts() : storage::sceneTexts(origin.scene);
  const storage::ReadScope read({ this->P->connected() }, this->P->Limits);
  this->P->requireSchema();
  return storage::selectPicture(this->P->conn(), origin, texts, format);
}
catch (...)
{
  storage::rethrowReadFailure(this->P->Limits);
}

void RayStore::deleteFrame(std::int64_t id)
{
  this->P->requireSchema();
  PGconn* conn = this->P->conn();
  const std::int64_t sceneId = pg::transaction(
    conn, pg::WriteBegin,
    [&]
    {
      // The row lock waits for the writers of its tiles (they hold it in key-share mode), so that
      // no table of rays is attached after the ones dropped here.
      pg::Result r = pg::Params().i64(id).exec(
        conn, "SELECT scene_id FROM frames WHERE id = $1 FOR UPDATE", "deleting the frame failed");
      if (PQntuples(r.get()) == 0)
      {
        throw StoreError("there is no frame " + std::to_string(id) + " to delete");
      }
      const std::int64_t scene = pg::getI64(r.get(), 0, 0);
      pg::Result tiles = pg::Params().i64(id).exec(conn,
                                                   "SELECT frame_id, tile FROM frame_tiles WHERE "
                                                   "frame_id = $1 AND ray_count > 0 ORDER BY tile",
                                                   "deleting the frame failed");
      storage::deleteFrameRow(conn, id, "deleting the frame failed");
      const std::string tables = storage::blockTableList(tiles.get());
      if (!tables.empty())
      {
        pg::exec(conn, "DROP TABLE " + tables, "deleting the frame's rays failed");
      }
      pg::exec(conn, "COMMIT", "committing the deletion failed");
      return scene;
    });
  storage::dropUnusedScenes(conn, sceneId);
}

namespace
{
/// Releases, once a predicate's read is over, the session-level advisory locks that the predicate
/// may have taken (pg_advisory_lock outlives the transaction): left held, they would block other
/// sessions for as long as this connection lives. The store takes transaction-level ones only.
struct PredicateLocksRelease
{
  PGconn* Conn;
  bool Active;
  ~PredicateLocksRelease()
  {
    if (this->Active && PQstatus(this->Conn) == CONNECTION_OK &&
        PQtransactionStatus(this->Conn) == PQTRANS_IDLE)
    {
      PQclear(PQexec(this->Conn, "SELECT pg_advisory_unlock_all()"));
    }
  }
};
}

std::vector<RayRecord> RayStore::readFrame(std::int64_t id, const std::string& predicate)
try
{
  // Checked before anything reaches the server: only what the grammar allows is sent.
  const std::string predicateSql = predicate.empty() ? predicate : rayPredicateSql(predicate);
  PGconn* conn = this->P->connected();
  const PredicateLocksRelease release{ conn, !predicate.empty() };
  // Ends before the release: no cancel reaches its statement.
  const storage::ReadScope read({ conn }, this->P->Limits);
  this->P->requireSchema();
  // REPEATABLE READ: the frame row, its tiles and its rays come from one snapshot. Always rolled
  // back, so that nothing a predicate might have done (set_config, ...) outlives the read.
  return pg::transaction(
    conn, pg::ReadBegin,
    [&]
    {
      pg::Result r = storage::completeFrameColumn(conn, id, "width, height, ray_count",
                                                  "reading the frame failed");
      const std::int64_t rayCount = pg::getI64(r.get(), 0, 2);
      // The records are allocated from these numbers: a row edited by hand must not decide that.
      checkFrameSize(id, pg::getI32(r.get(), 0, 0), pg::getI32(r.get(), 0, 1), rayCount);
      if (predicate.empty())
      {
        storage::requireReadMemory(id, rayCount, this->MemoryLimit);
      }
      std::vector<RayRecord> records =
        predicate.empty()
          ? this->P->readAllRays(id, rayCount)
          : readSelectedRays(conn, id, rayCount, predicateSql, this->PredicateTimeout);
      pg::exec(conn, "ROLLBACK", "ending the read failed");
      return records;
    });
}
catch (...)
{
  storage::rethrowReadFailure(this->P->Limits);
}

std::vector<RayPath> RayStore::readPaths(std::int64_t id)
try
{
  const storage::ReadScope read({ this->P->connected() }, this->P->Limits);
  this->P->requireSchema();
  PGconn* conn = this->P->conn();
  return pg::transaction(conn, pg::ReadBegin,
                         [&]
                         {
                           storage::completeFrameColumn(conn, id, "1", "reading the frame failed");
                           std::vector<RayPath> paths = storage::readPathRows(conn, id);
                           pg::exec(conn, "ROLLBACK", "ending the read failed");
                           return paths;
                         });
}
catch (...)
{
  storage::rethrowReadFailure(this->P->Limits);
}
}
