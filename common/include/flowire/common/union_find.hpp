#pragma once
/// @file union_find.hpp
/// @brief Disjoint sets over 0..n−1 with path halving; the representative of a set is its
/// smallest member (so results do not depend on the order of unions).
#include <algorithm>
#include <cstddef>
#include <numeric>
#include <vector>

namespace flowire {

class UnionFind {
 public:
  explicit UnionFind(std::size_t n) : parent_(n) { std::iota(parent_.begin(), parent_.end(), 0); }
  int find(int a) {
    while (parent_[static_cast<std::size_t>(a)] != a) {
      auto& p = parent_[static_cast<std::size_t>(a)];
      p = parent_[static_cast<std::size_t>(p)];
      a = p;
    }
    return a;
  }
  void unite(int a, int b) {
    a = find(a);
    b = find(b);
    if (a != b) parent_[static_cast<std::size_t>(std::max(a, b))] = std::min(a, b);
  }

 private:
  std::vector<int> parent_;
};

}  // namespace flowire
