// The ray predicates that RayStore::readFrame() accepts: a boolean expression over the columns of
// one ray of the view rays_v, and nothing else. The role that evaluates predicates cannot be kept
// from PostgreSQL's system catalogs and information functions (PUBLIC may read pg_settings,
// pg_roles, pg_proc, ..., and call version()), and what a predicate reads there leaks through
// which rays it selects. So a predicate is parsed here, against a grammar of its own, before it
// reaches the server, and only what the grammar allows is sent, written again token by token; the
// server's function asrt_selected_rays checks the tokens once more (schema version 6).
//
//   predicate   := disjunction
//   disjunction := conjunction { OR conjunction }
//   conjunction := negation { AND negation }
//   negation    := NOT negation | test
//   test        := sum [ comparison sum | IS [NOT] (NULL | TRUE | FALSE)
//                      | [NOT] BETWEEN sum AND sum | [NOT] IN ( literal { , literal } ) ]
//   comparison  := = | <> | != | < | <= | > | >=
//   sum         := term { (+ | -) term }
//   term        := factor { (* | / | %) factor }
//   factor      := unary { ^ unary }
//   unary       := (+ | -) unary | primary
//   primary     := number | string | TRUE | FALSE | NULL | column
//                | function ( [ disjunction { , disjunction } ] ) | ( disjunction )
//   literal     := [+ | -] number | string | TRUE | FALSE | NULL
//
// Keywords and names are case-insensitive; a number is PostgreSQL's (digits, a decimal point, an
// exponent), a string is '...' with '' for a quote. Refused: anything else (other names, SELECT and
// every other keyword, casts, quoted identifiers, comments, ';', '$', backslashes, characters
// outside printable ASCII), more than kMaxRayPredicateBytes, nesting deeper than
// kMaxRayPredicateDepth. PostgreSQL's own precedence decides what the sent text means: the grammar
// above only decides what may be sent.
#ifndef asrt_RayPredicate_h
#define asrt_RayPredicate_h

#include "asrtStoreModule.h"

#include <cstddef>
#include <string>
#include <vector>

namespace asrt
{
/// The longest predicate accepted, in bytes.
constexpr std::size_t kMaxRayPredicateBytes = 65536;
/// The deepest nesting accepted (parentheses, function arguments, NOT and signs), so that parsing
/// takes bounded stack whatever the text.
constexpr int kMaxRayPredicateDepth = 64;

/// The columns of rays_v that a predicate may name (all of them, in the view's order).
ASRTSTORE_EXPORT const std::vector<std::string>& rayPredicateColumns();

/// A function a predicate may call: pure arithmetic on numbers, `minArguments` to `maxArguments`
/// arguments.
struct RayPredicateFunction
{
  const char* name;
  int minArguments;
  int maxArguments;
};
/// The functions a predicate may call, by name.
ASRTSTORE_EXPORT const std::vector<RayPredicateFunction>& rayPredicateFunctions();

/// `predicate` checked against the grammar above and written again as the SQL the server is sent:
/// its tokens separated by single spaces, keywords in upper case, names in lower case. Throws
/// StoreError "the ray predicate was refused: ..." with the first thing refused and its position
/// (1-based, in bytes).
ASRTSTORE_EXPORT std::string rayPredicateSql(const std::string& predicate);
}

#endif
