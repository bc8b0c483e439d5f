// Every schema the store has had, frozen as the literal SQL that made it. A migration from an old
// version runs these texts and nothing generated from today's code: adding a ray field (or
// changing how the current version writes) must not change what an old database is upgraded
// from. A new layout is a new version with new literals; these never change. Internal to
// ASRT::Store.
#ifndef asrt_StoreSchemaHistory_h
#define asrt_StoreSchemaHistory_h

namespace asrt
{
namespace storage
{
/// Migration 1 (an empty database to version 1): tables and the view rays_v. A script.
extern const char* const SchemaV1;
/// Migration 2 (version 1 to 2): tiles. A script.
extern const char* const SchemaV2;
/// Migration 3 (version 2 to 3), first step: the tables of packed records. A script.
extern const char* const SchemaV3Tables;
/// Migration 3, second step, once per tile of version 2 after TileTableV3 made its table: its rays
/// re-packed. A tile statement.
extern const char* const SchemaV3ConvertTile;
/// Migration 3, last step, once the tiles are attached to ray_blocks_v3: the old table gone, the
/// paths, the views. A script.
extern const char* const SchemaV3Finish;
/// Version 3's table of one tile's rays: the table migration 3 makes for each tile, and the one
/// every write of the current version makes (LIKE the current ray_block_layout). A tile
/// statement.
extern const char* const TileTableV3;
/// Version 3's attachment of a tile's table to a partitioned parent. A tile statement.
extern const char* const AttachTileV3;
/// Version 4: the role that evaluates predicates, and the statement that creates it.
extern const char* const PredicateRoleV4;
extern const char* const CreatePredicateRoleV4;
/// Migration 4 (version 3 to 4), once the role exists and the migrating role may act as it: its
/// grants and the function that evaluates predicates as it. A script with {schema} and {user}.
extern const char* const SchemaV4;
/// Migration 5 (version 4 to 5), first step: the old ray_blocks and layout renamed, the new
/// layout of 264-byte records and its partitioned ray_blocks. A script.
extern const char* const SchemaV5Tables;
/// Migration 5, once per tile of version 4: its new table made beside the old one, its rays
/// re-packed into it, then the old one replaced by it (attached with AttachTileV3). Tile
/// statements; the last a tile script.
extern const char* const SchemaV5StageTile;
extern const char* const SchemaV5ConvertTile;
extern const char* const SchemaV5ReplaceTile;
/// Migration 5, last step of the rays: the old tables gone, rays_v with rays_per_pixel. A script.
extern const char* const SchemaV5Finish;
/// Migration 5's texts: the "rendering" section (JSON) that a frame's or scene's text without one
/// gets, that of singleRayRendering() as effectiveSceneText() writes it.
extern const char* const RenderingSectionV5;
/// Migration 6 (version 5 to 6), once the migrating role may act as the predicate role: the
/// function that evaluates predicates, replaced by one that checks the predicate's tokens first.
/// A script with {schema}; also what repairs version 4's function at version 6 and later.
extern const char* const SchemaV6;
/// The body of version 6's function, as pg_proc.prosrc holds it.
extern const char* const SelectedRaysBodyV6;
/// Migration 7 (version 6 to 7), first step: the old ray_blocks and layout renamed, the new
/// layout of 268-byte records (the word traced after dvdj) and its partitioned ray_blocks. A
/// script.
extern const char* const SchemaV7Tables;
/// Migration 7, once per tile of version 6: its new table made beside the old one, its rays
/// re-packed into it (each record traced), then the old one replaced by it (attached with
/// AttachTileV3). Tile statements; the last a tile script.
extern const char* const SchemaV7StageTile;
extern const char* const SchemaV7ConvertTile;
extern const char* const SchemaV7ReplaceTile;
/// Migration 7, last step of the rays: the old tables gone, rays_v with traced. A script.
extern const char* const SchemaV7Finish;
/// Migration 7, once the migrating role may act as the predicate role: the function that
/// evaluates predicates, replaced by one whose tokens may name traced. A script with {schema};
/// also what repairs an older function at version 7 and later.
extern const char* const SchemaV7;
/// The body of version 7's function, as pg_proc.prosrc holds it.
extern const char* const SelectedRaysBodyV7;
/// Migration 8 (version 7 to 8): the table of the keys interpolated frames were made from
/// (RayStore::recordInterpolatedFrame). A script.
extern const char* const SchemaV8;
/// Migration 9 (version 8 to 9): the table of frames' encoded pictures (RayStore::storePicture).
/// A script.
extern const char* const SchemaV9;
}
}

#endif
