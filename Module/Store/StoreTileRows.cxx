#include "StoreTileRows.h"

#include "PgSession.h"
#include "RayStore.h"
#include "StoreRecordCodec.h"
#include "StoreSchema.h"

#include <algorithm>

namespace asrt
{
namespace storage
{
namespace
{
/// The frame id and tile number of the tables of tiles, from the names of the tables in
/// pg_class c (both store-made numbers: see blockTable()).
const char* const TileTableNumbers =
  "SELECT m[1]::bigint, m[2]::integer FROM pg_class c CROSS JOIN LATERAL "
  "regexp_match(c.relname::text, '^ray_blocks_([0-9]+)_([0-9]+)$') AS m";

/// Dropping tables waits for the lock on them: two seconds lets reads and writes under way
/// finish, and otherwise gives up (the tables are left for a later call) rather than stall the
/// caller, whose own work is done.
void limitLockWait(PGconn* conn)
{
  pg::exec(conn, "SET LOCAL lock_timeout = '2s'", "setting a lock timeout failed");
}

/// Drops `tables` (comma-separated) that still exist.
void dropTablesIfExist(PGconn* conn, const std::string& tables, const std::string& what)
{
  pg::exec(conn, "DROP TABLE IF EXISTS " + tables, what);
}

/// Drops `ownFrame`'s (or, when negative, every frame's) tables of `candidates` that are orphans,
/// in the caller's transaction.
void dropOrphanTables(PGconn* conn, const PGresult* candidates, std::int64_t ownFrame)
{
  for (int row = 0; row < PQntuples(candidates); ++row)
  {
    const std::int64_t frame = pg::getI64(candidates, row, 0);
    const std::string table = blockTable(frame, pg::getI32(candidates, row, 1));
    if (ownFrame >= 0)
    {
      pg::Params().i64(frame).exec(conn, writerLock("pg_advisory_xact_lock"), "locking failed");
    }
    else if (pg::Result locked = pg::Params().i64(frame).exec(
               conn, writerLock("pg_try_advisory_xact_lock"), "locking failed");
             !pg::getBool(locked.get(), 0, 0))
    {
      continue; // its writer is still at work
    }
    pg::Result orphan = pg::Params().i64(frame).text(table).exec(
      conn,
      "SELECT NOT EXISTS (SELECT 1 FROM frames WHERE id = $1) AND EXISTS (SELECT 1 FROM "
      "pg_class WHERE oid = to_regclass($2) AND NOT relispartition)",
      "looking for the frame failed");
    if (pg::getBool(orphan.get(), 0, 0))
    {
      dropTablesIfExist(conn, table, "dropping the rays of a failed write failed");
    }
  }
}

bool idle(PGconn* conn)
{
  return PQstatus(conn) == CONNECTION_OK && PQtransactionStatus(conn) == PQTRANS_IDLE;
}
}

std::string writerLock(const char* function)
{
  return std::string("SELECT ") + function + "(" + std::to_string(WriterLockClass) +
         ", ($1::bigint & 2147483647)::integer)";
}

void loadTile(PGconn* conn, std::int64_t frameId, std::int32_t tile, std::size_t first,
              std::size_t count, const RecordProducer& next)
{
  if (count == 0)
  {
    return;
  }
  pg::exec(conn, createBlockTable(frameId, tile), "creating the table of the rays failed");
  // The table is fsynced at commit (wal_level = minimal) or at the next checkpoint: asking the
  // kernel to start writing its pages back every 2 MB keeps that fsync from writing the whole
  // table after the COPY, alone (bench/REPORT.md).
  pg::exec(conn, "SET LOCAL backend_flush_after = 256", "setting backend_flush_after failed");
  // Tests find a writer's backend by this statement's beginning ("COPY ray_blocks").
  pg::CopyWriter writer(conn,
                        "COPY " + blockTable(frameId, tile) +
                          " (frame_id, tile, block, first_ray, n, data) FROM STDIN (FORMAT "
                          "binary, FREEZE)",
                        "the rays");
  constexpr std::size_t blockSize = RayStore::kBlockSize;
  RayRecord block[blockSize];
  for (std::size_t at = 0, b = 0; at < count; at += blockSize, ++b)
  {
    const int n = int(std::min(blockSize, count - at));
    for (int m = 0; m < n; ++m)
    {
      next(first + at + std::size_t(m), block[m]);
    }
    writer.row(6);
    writer.i64(frameId);
    writer.i32(tile);
    writer.i32(std::int32_t(b));
    writer.i64(std::int64_t(at));
    writer.i32(n);
    encodeRecords(block, std::size_t(n),
                  writer.bytes(std::size_t(RayStore::kRecordBytes) * std::size_t(n)));
  }
  writer.finish();
}

void copyTile(PGconn* conn, std::int64_t frameId, std::int32_t tile, std::size_t count,
              const RecordProducer& next)
{
  if (count > 0)
  {
    loadTile(conn, frameId, tile, 0, count, next);
    pg::exec(conn, attachBlockTable("ray_blocks", frameId, tile), "attaching the rays failed");
  }
}

void recordTile(PGconn* conn, std::int64_t frameId, std::int32_t tile, std::int64_t count,
                const std::string& what)
{
  pg::Params().i64(frameId).i32(tile).i64(count).exec(
    conn,
    "INSERT INTO frame_tiles (frame_id, tile, ray_count, written_at) VALUES ($1, $2, $3, "
    "clock_timestamp())",
    what);
}

std::vector<TileRays> readTileRays(PGconn* conn, std::int64_t id, std::int64_t rayCount)
{
  pg::Result r = pg::Params().i64(id).exec(
    conn, "SELECT tile, ray_count FROM frame_tiles WHERE frame_id = $1 ORDER BY tile",
    "reading the frame's tiles failed");
  std::vector<TileRays> tiles;
  std::int64_t base = 0;
  for (int row = 0; row < PQntuples(r.get()); ++row)
  {
    const std::int64_t count = pg::getI64(r.get(), row, 1);
    tiles.push_back({ pg::getI32(r.get(), row, 0), base, count });
    base += count;
  }
  if (base != rayCount)
  {
    throw StoreError("frame " + std::to_string(id) + " is inconsistent: it says " +
                     std::to_string(rayCount) + " rays, its tiles " + std::to_string(base));
  }
  return tiles;
}

std::int64_t readTileGroup(PGconn* conn, std::int64_t id, const std::string& group,
                           const std::vector<TileRays>& tiles, std::vector<RayRecord>& records)
{
  // A parallel plan would only copy the rows once more, between processes.
  pg::exec(conn, "SELECT set_config('max_parallel_workers_per_gather', '0', true)",
           "reading the rays failed");
  std::int64_t got = 0;
  pg::Params()
    .i64(id)
    .text("{" + group + "}")
    .stream(conn,
            "SELECT tile, first_ray, n, data FROM ray_blocks WHERE frame_id = $1 AND tile = "
            "ANY($2::integer[])",
            "reading the rays failed",
            [&](const PGresult* row)
            {
              const std::int32_t tile = pg::getI32(row, 0, 0);
              const std::int64_t first = pg::getI64(row, 0, 1);
              const std::int32_t n = pg::getI32(row, 0, 2);
              const auto t = std::find_if(tiles.begin(), tiles.end(),
                                          [&](const TileRays& x) { return x.tile == tile; });
              if (t == tiles.end() || n < 1 || n > RayStore::kBlockSize || first < 0 ||
                  first + n > t->count ||
                  PQgetlength(row, 0, 3) != std::int64_t(n) * RayStore::kRecordBytes)
              {
                throw StoreError("reading the rays of frame " + std::to_string(id) +
                                 " failed: a stored block (tile " + std::to_string(tile) +
                                 ", first ray " + std::to_string(first) +
                                 ") does not fit the frame");
              }
              decodeRecords(PQgetvalue(row, 0, 3), std::size_t(n),
                            &records[std::size_t(t->base + first)]);
              got += n;
            });
  return got;
}

void dropUnattachedTiles(PGconn* conn, std::int64_t ownFrame) noexcept
{
  if (!idle(conn))
  {
    return;
  }
  // The lock is taken before the frame is looked for, in separate statements, so that the look
  // sees a writer's commit that came before the lock. Those tables are no partitions of
  // ray_blocks, so dropping them waits for nobody's reads.
  try
  {
    pg::Result r = pg::Params().i64(ownFrame).exec(
      conn,
      std::string(TileTableNumbers) +
        " WHERE c.relkind = 'r' AND NOT c.relispartition AND pg_table_is_visible(c.oid) AND ($1 < "
        "0 OR m[1]::bigint = $1)",
      "looking for the rays of failed writes failed");
    if (PQntuples(r.get()) == 0)
    {
      return;
    }
    pg::exec(conn, pg::WriteBegin, "starting a transaction failed");
    if (ownFrame >= 0)
    {
      limitLockWait(conn);
    }
    dropOrphanTables(conn, r.get(), ownFrame);
    pg::exec(conn, "COMMIT", "committing failed");
  }
  catch (const StoreError&)
  {
    pg::rollback(conn);
  }
}

void dropOrphanBlocks(PGconn* conn) noexcept
{
  if (!idle(conn))
  {
    return;
  }
  dropUnattachedTiles(conn);
  try
  {
    pg::transaction(
      conn, pg::WriteBegin,
      [&]
      {
        pg::Result r = pg::exec(conn,
                                std::string(TileTableNumbers) +
                                  " JOIN pg_inherits i ON c.oid = i.inhrelid WHERE i.inhparent = "
                                  "'ray_blocks'::regclass AND NOT EXISTS (SELECT 1 FROM frames f "
                                  "WHERE f.id = m[1]::bigint)",
                                "looking for the rays of deleted frames failed");
        const std::string tables = blockTableList(r.get());
        if (!tables.empty())
        {
          limitLockWait(conn);
          dropTablesIfExist(conn, tables, "dropping the rays of deleted frames failed");
        }
        pg::exec(conn, "COMMIT", "committing failed");
      });
  }
  catch (const StoreError&)
  {
    // Left for a later call.
  }
}

std::string blockTableList(const PGresult* frameTiles)
{
  std::string tables;
  for (int row = 0; row < PQntuples(frameTiles); ++row)
  {
    tables += (tables.empty() ? "" : ", ") +
              blockTable(pg::getI64(frameTiles, row, 0), pg::getI32(frameTiles, row, 1));
  }
  return tables;
}

int lockFrameForTile(PGconn* conn, std::int64_t frameId, int tile, const std::string& which)
{
  pg::Result r = pg::Params().i64(frameId).i32(tile).exec(
    conn,
    "SELECT f.status, f.tile_count, EXISTS (SELECT 1 FROM frame_tiles t WHERE t.frame_id = "
    "f.id AND t.tile = $2) FROM frames f WHERE f.id = $1 FOR KEY SHARE OF f",
    "looking for the frame failed");
  if (PQntuples(r.get()) == 0)
  {
    throw StoreError("writing " + which + " failed: there is no such frame");
  }
  const int tileCount = pg::getI32(r.get(), 0, 1);
  if (pg::getBool(r.get(), 0, 2))
  {
    throw StoreError("writing " + which + " failed: the tile is already written");
  }
  if (pg::getText(r.get(), 0, 0) != "writing")
  {
    throw StoreError("writing " + which + " failed: the frame is complete");
  }
  if (tile < 0 || tile >= tileCount)
  {
    throw StoreError("writing " + which + " failed: the frame has tiles 0 to " +
                     std::to_string(tileCount - 1));
  }
  return tileCount;
}

void completeIfLastTile(PGconn* conn, std::int64_t frameId, int tileCount)
{
  pg::Params().i64(frameId).exec(conn, "SELECT 1 FROM frames WHERE id = $1 FOR NO KEY UPDATE",
                                 "locking the frame failed");
  pg::Result r = pg::Params().i64(frameId).exec(
    conn,
    "SELECT count(*), coalesce(sum(ray_count), 0)::bigint FROM frame_tiles WHERE frame_id = $1",
    "counting the tiles failed");
  if (pg::getI64(r.get(), 0, 0) == tileCount)
  {
    pg::Params()
      .i64(frameId)
      .i64(pg::getI64(r.get(), 0, 1))
      .exec(conn,
            "UPDATE frames SET status = 'complete', ray_count = $2, write_seconds = "
            "extract(epoch FROM clock_timestamp() - created_at), completed_at = "
            "clock_timestamp() WHERE id = $1",
            "completing the frame failed");
  }
}
}
}
