#pragma once
// The refinement engine of every integration scheme (IntegrationScheme, integrator.h): one
// observer's pieces of the lit facets in priority queues by error, each in turn improved or
// split by the scheme's rule, until the error of the total is within the budget
// max(tolerance × |E|, floor), the evaluations run out, or what is left is frozen at the depth
// limit.
//
// A rule is a type, and the engine is compiled with it (refine<Rule>): a scheme is chosen once
// per observer, never per piece (schemes.h). A rule has
//
//   using Piece = ...;  // a piece of a coarse facet: `SubFacet facet`, `double error` (a
//                       // magnitude; +∞ or NaN where unbounded), `double value() const`
//   static constexpr bool kSignedErrors;  // some pieces' errors are signed changes, which may
//                       // cancel across pieces (the piece then has `bool signedError() const`
//                       // and `double change() const`; see Totals)
//   static constexpr bool kUnboundedErrorIsInfinite;  // the reported error is +∞ while any
//                       // piece's is unbounded (otherwise the sum of the bounded ones)
//   void seed(Refinement<Rule>&);  // adds the root pieces of its candidates
//   Step next(const Piece&, int max_depth) const;  // what the piece needs when it is popped
//   void improve(Piece&, Refinement<Rule>&);  // a better value and error for the same piece
//                                             // (it must not add pieces)
//   void split(const Piece& parent, Refinement<Rule>&);  // adds the children that replace it
//
// and reports its kernel evaluations to Refinement::count().

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "facets/integrator.h"
#include "facets/sum.h"

namespace glint::detail {

// An error estimate above this (W/m², far beyond any physical irradiance) is counted as
// unbounded instead of summed, and the running sums are compensated (sum.h). Both for the same
// incident: the running sums add every piece's error and take it out again when it changes,
// and near the target those bounds are many orders above the total. A plain double kept about
// 1e-16 of the largest as a residue, and two bounds near the largest double (a piece seen
// edge-on) overflowed it to +∞ for good (∞ − x stays ∞). Either way the running total never
// looked done, the exact total that would have said so was never taken, and one observer ran
// to the evaluation limit (4e6 evaluations and 1.3 GB of workspace at a point 0.14 m off the
// cylinder quarter's lit side, where 164 do). Counted, such a piece still blocks "done" until
// it is refined; summed below this, a billion pieces stay finite.
inline constexpr double kLargestSummedError = 1e100;

// Whether an error estimate counts as unbounded (NaN included): see kLargestSummedError.
inline bool unboundedError(double error_w_m2) { return !(error_w_m2 <= kLargestSummedError); }

// Heap priority: larger first. Pieces with a magnitude error are ranked by it; pieces with a
// signed error shallowest first (ties by |ΔE|), so a resolved region is refined a whole level
// at a time and its change of total stays the classical two-level estimate: refining only the
// largest |ΔE| would push a lobe's peak deeper than its tails and leave their same-signed
// O(h²) differences uncancelled.
struct HeapEntry {
  int rank;         // compared first: 0 for magnitudes, −depth for signed errors
  double priority;  // then the error
  std::uint32_t slot;
};

// Ties broken by slot, so the order never depends on anything but the input. (A function
// object, not a function pointer, so that the heap's sifting inlines it.)
struct HeapLess {
  bool operator()(const HeapEntry& a, const HeapEntry& b) const {
    if (a.rank != b.rank) return a.rank < b.rank;
    if (a.priority != b.priority) return a.priority < b.priority;
    return a.slot > b.slot;
  }
};

class PieceHeap {
 public:
  void clear() { entries_.clear(); }
  [[nodiscard]] bool empty() const { return entries_.empty(); }
  [[nodiscard]] const std::vector<HeapEntry>& entries() const { return entries_; }
  void push(int rank, double priority, std::uint32_t slot) {
    entries_.push_back({rank, priority, slot});
    std::push_heap(entries_.begin(), entries_.end(), HeapLess{});
  }
  std::uint32_t pop() {
    std::pop_heap(entries_.begin(), entries_.end(), HeapLess{});
    const std::uint32_t slot = entries_.back().slot;
    entries_.pop_back();
    return slot;
  }

 private:
  std::vector<HeapEntry> entries_;
};

// The engine's storage for one observer, kept in the workspace between observers.
template <class Piece>
struct RefineState {
  std::vector<Piece> pieces;  // by slot; a replaced piece's slot is reused
  std::vector<std::uint32_t> free_slots;
  PieceHeap bounded;                  // pieces with a magnitude error
  PieceHeap resolved;                 // pieces with a signed error
  std::vector<std::uint32_t> frozen;  // pieces that may not split further (depth limit)

  void clear() {
    pieces.clear();
    free_slots.clear();
    bounded.clear();
    resolved.clear();
    frozen.clear();
  }
};

// What a popped piece needs (Rule::next()).
enum class Step : std::uint8_t {
  Improve,  // a better estimate of the same piece
  Split,    // its children in its place
  Freeze,   // nothing: it is at the depth limit, and stays in the totals as it is
};

template <class Rule>
class Refinement {
 public:
  using Piece = typename Rule::Piece;

  Refinement(RefineState<Piece>& state, const IntegratorOptions& options)
      : s_(state), opt_(options) {
    s_.clear();
  }

  // A new piece: stored, accounted and queued by its error.
  void add(const Piece& piece) {
    std::uint32_t slot;
    if (!s_.free_slots.empty()) {
      slot = s_.free_slots.back();
      s_.free_slots.pop_back();
      s_.pieces[slot] = piece;
    } else {
      slot = static_cast<std::uint32_t>(s_.pieces.size());
      s_.pieces.push_back(piece);
    }
    enqueue(slot);
  }

  // Kernel evaluations spent by the rule.
  void count(std::int64_t evaluations) { result_.evaluations += evaluations; }

  // The error budget at the running total.
  [[nodiscard]] double budget() const { return budget(totals_.value()); }

  // The pieces that make up the total now (queued or frozen).
  [[nodiscard]] std::size_t livePieces() const { return s_.pieces.size() - s_.free_slots.size(); }

  ObserverResult run(Rule& rule) {
    rule.seed(*this);
    while (true) {
      if (done(totals_)) {
        totals_ = exactTotals();
        if (done(totals_)) break;
      }
      if (result_.evaluations >= opt_.max_evaluations) break;
      // Pieces proven only by their bounds cost no evaluations: were their bounds to stop
      // shrinking under splitting, they alone would exhaust memory (4^16 pieces at the depth
      // limit). Their number is held to a quarter of the evaluations allowed (at least 2^16);
      // past it the observer stops unconverged, its error the bounds it still holds.
      if (livePieces() > pieceLimit()) break;
      if (frozen_.unbounded > 0 || frozen_.magnitude() > budget()) break;
      PieceHeap* heap = nextHeap();
      if (heap == nullptr) break;  // everything left is frozen at the depth limit
      const std::uint32_t slot = heap->pop();
      Piece& piece = s_.pieces[slot];
      switch (rule.next(piece, opt_.max_depth)) {
        case Step::Freeze:
          freeze(slot);
          break;
        case Step::Improve:
          totals_.account(piece, -1);
          rule.improve(piece, *this);
          enqueue(slot);  // its error enters the queue and the sums afresh
          break;
        case Step::Split: {
          totals_.account(piece, -1);
          const Piece parent = piece;
          s_.free_slots.push_back(slot);
          rule.split(parent, *this);
          break;
        }
      }
    }
    totals_ = exactTotals();
    result_.irradiance_w_m2 = totals_.value();
    result_.error_estimate_w_m2 = totals_.error();
    if constexpr (Rule::kUnboundedErrorIsInfinite) {
      result_.error_estimate_w_m2 += totals_.unbounded > 0 ? kInf : 0.0;
    }
    result_.converged = done(totals_);
    return result_;
  }

 private:
  static constexpr double kInf = std::numeric_limits<double>::infinity();

  // The observer's error budget: Σ value, |Σ signed ΔE| + Σ magnitudes, and the number of
  // pieces whose error is unbounded, compensated (see kLargestSummedError). Signed pieces (their
  // samples resolve a smooth integrand) contribute their change ΔE = E'_O − E_O under one more
  // level: the observer's error estimate takes |Σ ΔE|, in which the alternating midpoint errors
  // across a resolved lobe cancel as they do in the true total.
  class Totals {
   public:
    void account(const Piece& piece, int sign) {
      value_sum_.add(sign * piece.value());
      if constexpr (Rule::kSignedErrors) {
        if (piece.signedError()) {
          change_sum_.add(sign * piece.change());
          return;
        }
      }
      if (unboundedError(piece.error)) {  // +∞, or a NaN that must count as +∞
        unbounded += sign;
      } else {
        magnitude_sum_.add(sign * piece.error);
      }
    }
    [[nodiscard]] double value() const { return value_sum_.value(); }
    [[nodiscard]] double signedChange() const { return change_sum_.value(); }
    [[nodiscard]] double magnitude() const { return magnitude_sum_.value(); }
    [[nodiscard]] double error() const {
      if constexpr (Rule::kSignedErrors) {
        return std::abs(signedChange()) + magnitude();
      } else {
        return magnitude();
      }
    }

    std::int64_t unbounded = 0;

   private:
    CompensatedSum value_sum_, change_sum_, magnitude_sum_;
  };

  [[nodiscard]] std::size_t pieceLimit() const {
    return static_cast<std::size_t>(std::max<std::int64_t>(opt_.max_evaluations / 4, 1 << 16));
  }

  [[nodiscard]] double budget(double total) const {
    return std::max(opt_.tolerance * std::abs(total), opt_.floor_w_m2);
  }
  [[nodiscard]] bool done(const Totals& t) const {
    return t.unbounded == 0 && t.error() <= budget(t.value());
  }

  void enqueue(std::uint32_t slot) {
    Piece& piece = s_.pieces[slot];
    // A NaN error would break the heap's order and hide the piece: it counts as unbounded.
    if (std::isnan(piece.error)) piece.error = kInf;
    totals_.account(piece, 1);
    if constexpr (Rule::kSignedErrors) {
      if (piece.signedError()) {
        s_.resolved.push(-static_cast<int>(piece.facet.depth), piece.error, slot);
        return;
      }
    }
    s_.bounded.push(0, piece.error, slot);
  }

  void freeze(std::uint32_t slot) {
    s_.frozen.push_back(slot);
    frozen_.account(s_.pieces[slot], 1);
    result_.depth_limited = true;
  }

  // Work on whichever part of the error stands in the way; null when both queues are empty.
  PieceHeap* nextHeap() {
    PieceHeap* heap = &s_.bounded;
    if constexpr (Rule::kSignedErrors) {
      const bool magnitude_first =
          totals_.unbounded > 0 || totals_.magnitude() >= std::abs(totals_.signedChange());
      heap = magnitude_first ? &s_.bounded : &s_.resolved;
      if (heap->empty()) heap = magnitude_first ? &s_.resolved : &s_.bounded;
    }
    return heap->empty() ? nullptr : heap;
  }

  // Exact totals over every live piece, to confirm what the running sums suggest.
  [[nodiscard]] Totals exactTotals() const {
    Totals t;
    for (const HeapEntry& h : s_.bounded.entries()) t.account(s_.pieces[h.slot], 1);
    for (const HeapEntry& h : s_.resolved.entries()) t.account(s_.pieces[h.slot], 1);
    for (std::uint32_t slot : s_.frozen) t.account(s_.pieces[slot], 1);
    return t;
  }

  RefineState<Piece>& s_;
  const IntegratorOptions& opt_;
  ObserverResult result_;
  Totals totals_;  // running; confirmed by exactTotals() before stopping
  Totals frozen_;  // what pieces at the depth limit hold: no further work can reduce it
};

// One observer's integration by @p rule: its pieces in @p state (cleared first).
template <class Rule>
ObserverResult refine(Rule& rule, RefineState<typename Rule::Piece>& state,
                      const IntegratorOptions& options) {
  return Refinement<Rule>(state, options).run(rule);
}

}  // namespace glint::detail
