// The scene texts of frames stored before anti-aliasing (schema versions 1 to 4): migration 5
// gives them the "rendering" section they were traced with; and of frames stored before the
// adaptive ray grid (versions 5 and 6): migration 7 writes out that they traced every pixel.
// Internal to ASRT::Store.
#ifndef asrt_StoreLegacyTexts_h
#define asrt_StoreLegacyTexts_h

#include <libpq-fe.h>

#include <string>

namespace asrt
{
namespace storage
{
/// `text` (a JSON object, as effectiveSceneText() wrote it) with the top-level "rendering"
/// section `section` (JSON) added if it has none, written as effectiveSceneText() writes a text
/// (nlohmann's dump: keys sorted, no whitespace); `text` unchanged if it has one. Throws
/// StoreError "<what>: ..." if `text` is no JSON object.
std::string withRenderingSection(const std::string& text, const char* section,
                                 const std::string& what);

/// Migration 5's texts, in the caller's transaction: every frame's effective text and every
/// scene's description without a rendering section get RenderingSectionV5, and the hashes that
/// identify them follow. A scene that then has the text of another scene row (one stored with
/// the section since) is merged into that row; a frame that then has another frame's identity
/// (the same frame stored again with the section) is refused (StoreError naming both), since one
/// of the two has to go and which one is the user's choice.
void addRenderingSections(PGconn* conn, const std::string& what);

/// `text` (a JSON object) with "gridLattice": 1 added to its "rendering" section if that has no
/// lattice, written as effectiveSceneText() writes a text; `text` unchanged otherwise. Before the
/// grid, a text without the lattice meant every pixel traced; since, it means the default grid.
std::string withGridLattice(const std::string& text, const std::string& what);

/// Migration 7's texts, in the caller's transaction: every frame's effective text and every
/// scene's description whose rendering section has no "gridLattice" gets "gridLattice": 1, and
/// the hashes follow, scene rows merging and duplicate frames refused as in
/// addRenderingSections().
void addGridLattices(PGconn* conn, const std::string& what);
}
}

#endif
