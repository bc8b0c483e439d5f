// The rays of a frame in the database: each tile's table of packed records (loaded, attached,
// read, dropped) and its row of frame_tiles. Internal to ASRT::Store.
#ifndef asrt_StoreTileRows_h
#define asrt_StoreTileRows_h

#include "RayRecord.h"

#include <libpq-fe.h>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace asrt
{
namespace storage
{
/// Produces record `index` of a frame or tile (RayStore::writeFrame's `next`).
using RecordProducer = std::function<void(std::size_t, RayRecord&)>;

/// The class of the two-key advisory lock (this class, the frame id's low 31 bits) that a
/// parallel write's main transaction holds from its frame's insertion to its end: the number
/// after SchemaLockKey ("ASRT"), so that the store's locks stay together and apart from other
/// applications'. The tables that the write's helper connections commit are not attached until
/// the main transaction attaches them just before its commit; until then the lock tells
/// dropUnattachedTiles() that they are not orphans.
constexpr int WriterLockClass = 1095979605;
/// The statement that takes (`function` pg_advisory_xact_lock or pg_try_advisory_xact_lock) the
/// writer lock of frame $1.
std::string writerLock(const char* function);

/// Writes the records of one tile into a table of its own, created here and loaded in one COPY
/// FREEZE, records [first, first + count) of `next`; not attached to ray_blocks. The caller's
/// transaction must be READ COMMITTED (COPY FREEZE refuses a transaction that holds a snapshot).
/// An empty tile has no table.
void loadTile(PGconn* conn, std::int64_t frameId, std::int32_t tile, std::size_t first,
              std::size_t count, const RecordProducer& next);
/// loadTile() of records [0, count) and the attachment of its table to ray_blocks, in the
/// caller's transaction.
void copyTile(PGconn* conn, std::int64_t frameId, std::int32_t tile, std::size_t count,
              const RecordProducer& next);
/// The row of frame_tiles that says tile `tile` of the frame is written, with `count` rays.
void recordTile(PGconn* conn, std::int64_t frameId, std::int32_t tile, std::int64_t count,
                const std::string& what);

/// Where each tile's rays start in a frame, and how many it has, in tile order.
struct TileRays
{
  std::int32_t tile;
  std::int64_t base, count;
};
/// The tiles of frame `id`; throws StoreError unless their rays add up to `rayCount`.
std::vector<TileRays> readTileRays(PGconn* conn, std::int64_t id, std::int64_t rayCount);
/// Reads the rays of the tiles `group` (comma-separated numbers) of frame `id` into their places
/// in `records` (laid out as `tiles` says); returns how many it read. Rows come in whatever order
/// the server finds them; each says where its rays go. The table's keys and checks (one row per
/// block, first_ray = kBlockSize × block, n ≤ kBlockSize) make the rows' ranges disjoint, so a
/// count that adds up covers every ray exactly once.
std::int64_t readTileGroup(PGconn* conn, std::int64_t id, const std::string& group,
                           const std::vector<TileRays>& tiles, std::vector<RayRecord>& records);

/// Drops the tables of tiles that a parallel write's helper connection committed but whose frame
/// never committed (the writer failed or died): tables ray_blocks_<frame>_<tile> that are not
/// partitions, whose writer's lock is free and whose frame does not exist. `ownFrame` >= 0: only
/// that frame's, by its own writer after a failure, waiting a moment for its main backend to let
/// go (a terminated backend may still be exiting). Best effort: never throws (left for a later
/// call).
void dropUnattachedTiles(PGconn* conn, std::int64_t ownFrame = -1) noexcept;
/// Drops the tables of rays whose frame is gone (replaced, or deleted with plain SQL), and those
/// of dropUnattachedTiles(). Dropping a table of ray_blocks locks ray_blocks exclusively, so this
/// waits at most a moment for reads under way and otherwise leaves the tables for a later call
/// (rays_v and readFrame never show them). Never throws.
void dropOrphanBlocks(PGconn* conn) noexcept;
/// The tile count of frame `frameId`, locked FOR KEY SHARE in the caller's transaction, after
/// checking that `tile` can be written into it. FOR KEY SHARE keeps the frame from being deleted
/// under the COPY without blocking the other tiles' writers (the foreign keys take the same lock
/// anyway).
int lockFrameForTile(PGconn* conn, std::int64_t frameId, int tile, const std::string& which);
/// Completes frame `frameId` if its tiles are all written. Only now, after the COPY, is the frame
/// row locked, so tiles are written in parallel and only this short step is serialised. Under the
/// lock, the count (a fresh snapshot) sees every tile committed before and this one: of two last
/// tiles committing together, the second to get the lock sees the first's row and completes the
/// frame. FOR NO KEY UPDATE, not FOR UPDATE, which would conflict with the other writers'
/// key-share locks and deadlock two of them.
void completeIfLastTile(PGconn* conn, std::int64_t frameId, int tileCount);
/// The tables of the rows of `frameTiles` (frame id and tile number, binary), comma-separated.
std::string blockTableList(const PGresult* frameTiles);
}
}

#endif
