#include "fullarm/haptics/minima.hpp"

#include <algorithm>
#include <tuple>

namespace fullarm::haptics {

// §3.2.1: global search within the cutoff, pruning and local descent of the minima (reports/equations.md).
void pruneMinima(std::vector<LocalMinimum>& candidates, double radius_m, std::span<const LocalMinimum> baseline) {
  std::stable_sort(candidates.begin(), candidates.end(), [](const LocalMinimum& a, const LocalMinimum& b) {
    return std::tie(a.link, a.object, a.distance_m) < std::tie(b.link, b.object, b.distance_m);
  });
  const double r2 = radius_m * radius_m;
  auto near = [r2](const LocalMinimum& a, const LocalMinimum& b) {
    return a.link == b.link && a.object == b.object && (a.p_L - b.p_L).squaredNorm() <= r2 &&
           (a.p_O - b.p_O).squaredNorm() <= r2;
  };
  std::vector<LocalMinimum> accepted;
  accepted.reserve(candidates.size());
  for (const LocalMinimum& c : candidates) {
    if (radius_m > 0.0) {
      const bool in_baseline =
          std::any_of(baseline.begin(), baseline.end(), [&](const LocalMinimum& b) { return near(c, b); });
      if (in_baseline) continue;
      // Accepted minima of the same pair are contiguous at the back of `accepted`.
      bool covered = false;
      for (auto it = accepted.rbegin(); it != accepted.rend() && it->link == c.link && it->object == c.object; ++it) {
        if (near(c, *it)) {
          covered = true;
          break;
        }
      }
      if (covered) continue;
    }
    accepted.push_back(c);
  }
  candidates = std::move(accepted);
}

// §3.2.1: global search within the cutoff, pruning and local descent of the minima (reports/equations.md).
int adoptGlobalMinima(std::vector<LocalMinimum>& tracked, std::vector<LocalMinimum> fresh, double radius_m) {
  std::erase_if(fresh, [&tracked](const LocalMinimum& f) {
    return std::any_of(tracked.begin(), tracked.end(), [&f](const LocalMinimum& t) { return sameFeaturePair(f, t); });
  });
  pruneMinima(fresh, radius_m, tracked);
  tracked.insert(tracked.end(), fresh.begin(), fresh.end());
  return static_cast<int>(fresh.size());
}

}  // namespace fullarm::haptics
