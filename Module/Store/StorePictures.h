// The rows of frames' encoded pictures (RayStore::storePicture, readPicture). Internal to
// ASRT::Store.
#ifndef asrt_StorePictures_h
#define asrt_StorePictures_h

#include "PgSession.h"
#include "RayStore.h"
#include "StoreFrameRows.h"

#include <optional>
#include <string>

namespace asrt
{
namespace storage
{
/// Throws StoreError naming the field of `picture` that cannot be stored.
void checkPicture(const FramePicture& picture);
/// Stores the picture of `origin` (its scene's texts `texts` where it is an interpolated frame).
void upsertPicture(PGconn* conn, const PictureOrigin& origin, const SceneTexts& texts,
                   const FramePicture& picture);
/// The picture of `origin` in `format`, if it serves.
std::optional<FramePicture> selectPicture(PGconn* conn, const PictureOrigin& origin,
                                          const SceneTexts& texts, const std::string& format);
}
}

#endif
