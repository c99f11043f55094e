// The adaptive field's store of candidate pieces: one entry per distinct piece, whichever
// block or thread brings it.
#include "observers/detail/piece_pool.h"

#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include <set>
#include <vector>

namespace glint::field {
namespace {

// Piece k of coarse facet `coarse` at depth 2: a distinct barycentric triangle per k.
Candidate piece(std::uint32_t coarse, int k) {
  Candidate c;
  c.facet.coarse = coarse;
  c.facet.depth = 2;
  const double u = 0.25 * (k % 4), v = 0.25 * (k / 4);
  c.facet.bary = {Vec3(1.0 - u - v, u, v), Vec3(0.75 - u - v, u + 0.25, v),
                  Vec3(0.75 - u - v, u, v + 0.25)};
  c.geometry.area_m2 = coarse + 0.01 * k;  // to tell the stored copies apart
  return c;
}

TEST(PiecePool, TheSamePieceFromAnyBlockIsOneEntry) {
  PiecePool pool;
  const std::uint32_t a = pool.intern(piece(3, 1));
  const std::uint32_t b = pool.intern(piece(3, 2));
  const std::uint32_t c = pool.intern(piece(4, 1));  // same triangle, another coarse facet
  EXPECT_NE(a, b);
  EXPECT_NE(a, c);
  EXPECT_EQ(pool.intern(piece(3, 1)), a) << "a piece met again must not be stored again";
  EXPECT_EQ(pool.size(), 3u);
  EXPECT_EQ(pool[c].facet.coarse, 4u);
  EXPECT_DOUBLE_EQ(pool[b].geometry.area_m2, 3.02);
}

TEST(PiecePool, ThreadsInterningTogetherAgreeOnEveryIndex) {
  // 8 coarse facets × 16 pieces, each interned 64 times from whichever thread runs it.
  constexpr int kFacets = 8, kPieces = 16, kRepeats = 64;
  PiecePool pool;
  std::vector<std::uint32_t> index(kFacets * kPieces * kRepeats);
  tbb::parallel_for(0, static_cast<int>(index.size()), [&](int n) {
    const int which = n % (kFacets * kPieces);
    index[static_cast<std::size_t>(n)] =
        pool.intern(piece(static_cast<std::uint32_t>(which / kPieces), which % kPieces));
  });
  EXPECT_EQ(pool.size(), static_cast<std::size_t>(kFacets * kPieces));
  std::set<std::uint32_t> distinct;
  for (std::size_t n = 0; n < index.size(); ++n) {
    const int which = static_cast<int>(n) % (kFacets * kPieces);
    ASSERT_EQ(index[n], index[static_cast<std::size_t>(which)]) << "interning " << n;
    const Candidate& stored = pool[index[n]];
    EXPECT_EQ(stored.facet.coarse, static_cast<std::uint32_t>(which / kPieces)) << n;
    EXPECT_EQ(stored.facet.bary, piece(stored.facet.coarse, which % kPieces).facet.bary) << n;
    distinct.insert(index[n]);
  }
  EXPECT_EQ(distinct.size(), static_cast<std::size_t>(kFacets * kPieces));
}

}  // namespace
}  // namespace glint::field
