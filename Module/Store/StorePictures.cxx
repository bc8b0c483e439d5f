// Frames' encoded pictures. A whole frame's picture is tied to the frame's row (deleted with it);
// an interpolated frame's to the record of the keys it was made between: it is stored and served
// only while interpolated_frames records exactly those keys for its frame and recipe, each a
// complete frame, so that a picture never outlives what it was made from.
#include "StorePictures.h"

#include <cmath>

namespace asrt
{
namespace storage
{
namespace
{
const char* const PictureColumns = "p.format, p.method::integer, p.estimated_psnr, "
                                   "p.settings_psnr, p.share_retraced, p.rays, p.bytes";

/// The keys as a bigint[] literal, "{1,2,3}".
std::string keyArray(const std::vector<std::int64_t>& keys)
{
  std::string array = "{";
  for (std::int64_t id : keys)
    array += (array.size() > 1 ? "," : "") + std::to_string(id);
  return array + "}";
}

/// The condition that the interpolated frame $1 (its text), recipe $2, is recorded as made
/// between exactly the keys $3, each a complete frame.
const char* const RecordedBetweenKeys =
  "EXISTS (SELECT 1 FROM interpolated_frames f WHERE f.frame_hash = sha256($1) AND f.recipe = $2 "
  "AND f.key_frame_ids = $3::bigint[]) AND (SELECT count(*) FROM frames WHERE id = ANY "
  "($3::bigint[]) AND status = 'complete') = (SELECT count(DISTINCT k) FROM unnest($3::bigint[]) "
  "k)";

FramePicture pictureOfRow(const PGresult* r)
{
  FramePicture p;
  p.format = pg::getText(r, 0, 0);
  p.method = pg::getI32(r, 0, 1);
  p.estimatedPsnr = pg::getF64(r, 0, 2);
  p.settingsPsnr = pg::getF64(r, 0, 3);
  p.shareRetraced = pg::getF64(r, 0, 4);
  p.rays = pg::getF64(r, 0, 5);
  p.bytes = pg::getText(r, 0, 6);
  return p;
}

void checkFormat(const std::string& format)
{
  bool valid = !format.empty() && format.size() <= 32;
  for (char c : format)
    valid = valid && ((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '.');
  if (!valid)
    throw StoreError("picture format \"" + format.substr(0, 40) +
                     "\" is not 1 to 32 of a-z, 0-9 and '.'");
}
}

void checkPicture(const FramePicture& picture)
{
  checkFormat(picture.format);
  if (picture.method < 0 || picture.method > 255)
    throw StoreError("picture method " + std::to_string(picture.method) + " is outside 0..255");
  if (!(picture.shareRetraced >= 0 && picture.shareRetraced <= 1))
    throw StoreError("picture share re-traced " + std::to_string(picture.shareRetraced) +
                     " is outside [0, 1]");
  if (!(picture.rays >= 0))
    throw StoreError("picture rays " + std::to_string(picture.rays) + " is negative or NaN");
  if (std::isnan(picture.estimatedPsnr) || std::isnan(picture.settingsPsnr))
    throw StoreError("picture PSNR is NaN");
}

void upsertPicture(PGconn* conn, const PictureOrigin& origin, const SceneTexts& texts,
                   const FramePicture& picture)
{
  checkPicture(picture);
  const char* const facts = "method, estimated_psnr, settings_psnr, share_retraced, rays, bytes";
  const char* const update =
    "DO UPDATE SET method = EXCLUDED.method, estimated_psnr = EXCLUDED.estimated_psnr, "
    "settings_psnr = EXCLUDED.settings_psnr, share_retraced = EXCLUDED.share_retraced, rays = "
    "EXCLUDED.rays, bytes = EXCLUDED.bytes, key_frame_ids = EXCLUDED.key_frame_ids, created_at "
    "= now() RETURNING 1";
  pg::Params params;
  std::string sql;
  if (origin.wholeFrame)
  {
    params.i64(*origin.wholeFrame);
    sql = std::string("INSERT INTO frame_pictures (frame_id, format, ") + facts +
          ") SELECT $1, $2, $3, $4, $5, $6, $7, $8 WHERE EXISTS (SELECT 1 FROM frames WHERE id = "
          "$1 AND status = 'complete') ON CONFLICT (frame_id, format) WHERE frame_id IS NOT NULL " +
          update;
  }
  else
  {
    if (origin.keys.empty() || origin.keys.size() > 16)
      throw StoreError("picture of an interpolated frame: " + std::to_string(origin.keys.size()) +
                       " keys (1 to 16)");
    params.bytes(texts.frame).text(origin.recipe).text(keyArray(origin.keys));
    sql = std::string("INSERT INTO frame_pictures (frame_hash, recipe, key_frame_ids, format, ") +
          facts + ") SELECT sha256($1), $2, $3::bigint[], $4, $5, $6, $7, $8, $9, $10 WHERE " +
          RecordedBetweenKeys +
          " ON CONFLICT (frame_hash, recipe, format) WHERE frame_id IS NULL " + update;
  }
  params.text(picture.format)
    .i32(picture.method)
    .f64(picture.estimatedPsnr)
    .f64(picture.settingsPsnr)
    .f64(picture.shareRetraced)
    .f64(picture.rays)
    .bytes(picture.bytes);
  pg::Result r = params.exec(conn, sql, "storing a picture failed");
  if (PQntuples(r.get()) == 0)
    throw StoreError(
      std::string(kPictureRefused) +
      (origin.wholeFrame
         ? "frame " + std::to_string(*origin.wholeFrame) + " is no complete stored frame"
         : "the frame is not recorded as interpolated by \"" + origin.recipe +
             "\" between the complete frames " + keyArray(origin.keys)));
}

std::optional<FramePicture> selectPicture(PGconn* conn, const PictureOrigin& origin,
                                          const SceneTexts& texts, const std::string& format)
{
  checkFormat(format);
  pg::Params params;
  std::string sql = std::string("SELECT ") + PictureColumns + " FROM frame_pictures p WHERE ";
  if (origin.wholeFrame)
  {
    params.i64(*origin.wholeFrame).text(format);
    sql += "p.frame_id = $1 AND p.format = $2";
  }
  else
  {
    if (origin.keys.empty() || origin.keys.size() > 16)
      return std::nullopt;
    params.bytes(texts.frame).text(origin.recipe).text(keyArray(origin.keys)).text(format);
    sql += std::string("p.frame_id IS NULL AND p.frame_hash = sha256($1) AND p.recipe = $2 AND "
                       "p.key_frame_ids = $3::bigint[] AND p.format = $4 AND ") +
           RecordedBetweenKeys;
  }
  pg::Result r = params.exec(conn, sql, "reading a picture failed");
  if (PQntuples(r.get()) == 0)
    return std::nullopt;
  return pictureOfRow(r.get());
}
}
}
