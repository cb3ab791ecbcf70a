#include "mc_storage.hpp"

namespace granuflow::montecarlo {

void Storage::reset(uint32_t primaries) {
  n_.assign(primaries, 1u);
  head_.assign(primaries, kNone);
  t_dep_.clear();
  next_.clear();
  free_.clear();
}

void Storage::deposit(uint32_t i, double t) {
  int32_t d;
  if (!free_.empty()) {
    d = free_.back();
    free_.pop_back();
    t_dep_[static_cast<size_t>(d)] = t;
  } else {
    d = static_cast<int32_t>(t_dep_.size());
    t_dep_.push_back(t);
    next_.push_back(kNone);
  }
  next_[static_cast<size_t>(d)] = head_[i];
  head_[i] = d;
}

void Storage::remove(uint32_t j) {
  n_[j] = n_.back();
  head_[j] = head_.back();
  n_.pop_back();
  head_.pop_back();
}

void Storage::duplicate() {
  const uint32_t count = size();
  n_.reserve(2 * static_cast<size_t>(count));
  head_.reserve(2 * static_cast<size_t>(count));
  for (uint32_t i = 0; i < count; ++i) {
    n_.push_back(n_[i]);
    head_.push_back(kNone);
    // Copy the list in its order (indices, not pointers: the droplet arrays may grow meanwhile).
    int32_t prev = kNone;
    for (int32_t d = head_[i]; d != kNone; d = next_[static_cast<size_t>(d)]) {
      const double t = t_dep_[static_cast<size_t>(d)];
      int32_t c;
      if (!free_.empty()) {
        c = free_.back();
        free_.pop_back();
        t_dep_[static_cast<size_t>(c)] = t;
      } else {
        c = static_cast<int32_t>(t_dep_.size());
        t_dep_.push_back(t);
        next_.push_back(kNone);
      }
      next_[static_cast<size_t>(c)] = kNone;
      if (prev == kNone)
        head_[count + i] = c;
      else
        next_[static_cast<size_t>(prev)] = c;
      prev = c;
    }
  }
}

size_t Storage::bytes() const {
  return n_.capacity() * sizeof(uint32_t) + head_.capacity() * sizeof(int32_t) + t_dep_.capacity() * sizeof(double) +
         next_.capacity() * sizeof(int32_t) + free_.capacity() * sizeof(int32_t);
}

}  // namespace granuflow::montecarlo
