// Particle and droplet storage of one Monte Carlo replica, structure of arrays: per agglomerate its number of primary
// particles and the head of its droplet list; per droplet its deposition time and the next droplet on the same
// agglomerate (an intrusive singly linked list, so that a coalescence joins two lists without moving droplets). Freed
// droplet slots are reused; after warm-up no event allocates.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

namespace granuflow::montecarlo {

class Storage {
 public:
  static constexpr int32_t kNone = -1;
  static constexpr double kBytesPerAgglomerate = sizeof(uint32_t) + sizeof(int32_t);
  static constexpr double kBytesPerDroplet = sizeof(double) + sizeof(int32_t);

  void reset(uint32_t primaries);
  uint32_t size() const { return static_cast<uint32_t>(n_.size()); }

  uint32_t& n(uint32_t i) { return n_[i]; }
  uint32_t n(uint32_t i) const { return n_[i]; }
  int32_t& head(uint32_t i) { return head_[i]; }
  int32_t head(uint32_t i) const { return head_[i]; }
  double t_dep(int32_t d) const { return t_dep_[static_cast<size_t>(d)]; }
  int32_t& next(int32_t d) { return next_[static_cast<size_t>(d)]; }
  int32_t next(int32_t d) const { return next_[static_cast<size_t>(d)]; }

  // A droplet deposited at time t on agglomerate i (put first in its list).
  void deposit(uint32_t i, double t);
  void free_droplet(int32_t d) { free_.push_back(d); }
  // Agglomerate j leaves (its droplets must have been moved or freed): the last one takes its place.
  void remove(uint32_t j);
  // Periodic regulation (paper 003, section 7.7.1): an identical copy of the sample volume joins it.
  void duplicate();

  size_t droplet_slots() const { return t_dep_.size(); }
  size_t bytes() const;  // allocated bytes of every array

  std::vector<uint32_t>& primaries() { return n_; }

 private:
  std::vector<uint32_t> n_;
  std::vector<int32_t> head_;
  std::vector<double> t_dep_;
  std::vector<int32_t> next_;
  std::vector<int32_t> free_;
};

}  // namespace granuflow::montecarlo
