// The rows that describe frames: scenes, frames and the paths of a frame's rays. Internal to
// ASRT::Store.
#ifndef asrt_StoreFrameRows_h
#define asrt_StoreFrameRows_h

#include "PgSession.h"
#include "RayStore.h"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace asrt
{
namespace storage
{
/// The scene's identity texts: the whole effective description (the frame), and the description
/// without the parameters stored as frame columns (the scene shared by the frames of a movie).
struct SceneTexts
{
  std::string frame;
  std::string scene;
};
/// Throws StoreError for a description that cannot be stored (not serialisable, not valid UTF-8,
/// a NUL).
SceneTexts sceneTexts(const SceneDescription& d);

/// The id of the scene row, created if missing. The scene row is shared by every frame of the
/// scene (a movie's frames differ only in their parameters). It is created in its own short
/// transaction and never locked by a frame's write: an upsert inside the frame's transaction
/// would hold its row lock for the whole COPY and serialise every other writer of the scene.
/// The row may be removed again (see dropUnusedScenes) before the frame's row refers to it:
/// insertFrame() then throws SceneVanished and the writer asks again.
std::int64_t sceneRow(PGconn* conn, const SceneTexts& texts);
/// Removes scene rows that no frame uses: `sceneId`'s, or all of them when it is negative.
/// They are left by a failed write (the scene row is committed before the frame's transaction)
/// or by the deletion of a scene's last frame. A row that a frame being written refers to is
/// locked by that writer and skipped; a writer that looked the row up but has not referred to it
/// yet looks it up again (SceneVanished). Best effort and never throws: the caller may be
/// handling another error, and an unused scene row is only a few kB of description that the
/// next write of the scene reuses.
void dropUnusedScenes(PGconn* conn, std::int64_t sceneId) noexcept;

/// The scene row a frame was to use disappeared before the frame's row referenced it (an unused
/// scene row is removed after a failed write or the deletion of its last frame): look it up again.
struct SceneVanished
{
};

/// Inserts the row of a frame being written ('writing'); returns its id. With `ifAbsent`, a frame
/// of the same identity makes the result empty instead of an error (the caller then looks at
/// that frame).
std::optional<std::int64_t> insertFrame(PGconn* conn, std::int64_t sceneId, const SceneTexts& texts,
                                        const SceneDescription& scene, const std::string& label,
                                        int tileCount, bool ifAbsent);

/// The frame of a scene text's identity, whatever its status; with `lock`, locked (FOR UPDATE)
/// in the caller's transaction.
struct FrameOfIdentity
{
  std::int64_t id;
  std::string status;
  int tileCount;
  std::string label;
};
std::optional<FrameOfIdentity> findFrameOfIdentity(PGconn* conn, const SceneTexts& texts,
                                                   bool lock);
/// The frame being written has the identity of `old`: throws StoreError unless it may replace it
/// (a complete frame, and `replace`). A frame being written in tiles is never replaced: that
/// would pull it from under the ranks writing them. writeFrame() and checkFrameIdentity() both
/// decide with this.
void refuseIdentityClash(const FrameOfIdentity& old, bool replace);

/// What beginTiledFrame()'s transaction did: the 'writing' frame of this identity, inserted or
/// joined (none when the row it conflicted with vanished before it could be looked at), and
/// whether a complete frame was deleted for it.
struct TiledFrameStart
{
  std::optional<std::int64_t> id;
  bool replaced = false;
};
/// beginTiledFrame()'s transaction: inserts the 'writing' frame of this identity, or joins the one
/// there, or deletes a complete one (`replace`) for it, and commits.
TiledFrameStart beginOrJoinTiledFrame(PGconn* conn, std::int64_t sceneId, const SceneTexts& texts,
                                      const SceneDescription& scene, const std::string& label,
                                      int tileCount, bool replace);

/// The complete frame `old` has the identity of the one being written: a duplicate, refused
/// unless `replace`, which deletes its row (its paths and tiles go with it). Its tables of rays
/// are dropped after the commit (see dropOrphanBlocks: dropping them here would lock ray_blocks
/// for the whole write); until then nothing shows them.
void deleteReplaced(PGconn* conn, const FrameOfIdentity& old, bool replace);
/// Deletes the row of frame `id` (its tiles and paths go with it).
void deleteFrameRow(PGconn* conn, std::int64_t id, const std::string& what);

/// The frame rows of complete frames, `condition` (SQL after "WHERE <complete>", e.g. " AND f.id
/// = $1") selecting among them with `params`.
std::vector<FrameInfo> selectFrames(PGconn* conn, const pg::Params& params,
                                    const std::string& condition, const std::string& what);
/// The value of `column` of complete frame `id`; throws StoreError "there is no frame <id>".
pg::Result completeFrameColumn(PGconn* conn, std::int64_t id, const std::string& column,
                               const std::string& what);

/// Refuses (StoreError naming the frame and its ray_count) a read of all `rayCount` records of
/// frame `id` that would allocate more than `limit` bytes (0: defaultMemoryLimit()).
void requireReadMemory(std::int64_t id, std::int64_t rayCount, double limit);

/// Refuses paths that the frame cannot hold: a pixel outside it, two paths of one pixel, more
/// points than a bytea holds.
void checkPaths(const SceneDescription& scene, const std::vector<RayPath>& paths);
/// Writes the paths of frame `frameId`, in the given order, in the caller's transaction.
void copyPaths(PGconn* conn, std::int64_t frameId, const std::vector<RayPath>& paths);
/// The paths of frame `id`, in the order written.
std::vector<RayPath> readPathRows(PGconn* conn, std::int64_t id);
/// The keys an interpolated frame was made from (RayStore::recordInterpolatedFrame): recorded,
/// replacing an earlier record of the frame and recipe; throws StoreError for an empty recipe, a
/// key count outside 1..16, or a key that is no complete frame.
void recordInterpolatedKeys(PGconn* conn, const SceneTexts& texts, const std::string& recipe,
                            const std::vector<std::int64_t>& keys);
/// The keys recorded for the frame of `texts` and `recipe`, in order, if any.
std::optional<std::vector<std::int64_t>> interpolatedKeys(PGconn* conn, const SceneTexts& texts,
                                                          const std::string& recipe);
/// Whether a complete frame of some of the pixels of `scene` (`texts` its texts) is stored: its
/// identity but for the subset and the rendering, which both sides leave out (so `scene` may name
/// a subset itself; RayStore::hasSubsetFrames).
bool subsetFramesExist(PGconn* conn, const SceneTexts& texts, const SceneDescription& scene);
/// The ids of the complete frames of some of the pixels of `scene` (`texts` its texts) at its
/// rendering, in the order stored: its identity and rendering, the subset left out on both sides
/// (RayStore::readSubsetRecords).
std::vector<std::int64_t> subsetFrameIds(PGconn* conn, const SceneTexts& texts,
                                         const SceneDescription& scene);
}
}

#endif
