#include "granuflow/interrupt.hpp"

#include <atomic>
#include <utility>

namespace granuflow {

namespace {
std::atomic<bool> g_flag{false};
std::atomic<int> g_scopes{0};  // outermost scopes alive on any thread
thread_local InterruptScope* t_scope = nullptr;
}  // namespace

// The flag lives while any scope does: it reaches the runs on every thread of the interrupted work (and the grid
// check's solve beside a run), and no run outside a scope ever finds it left over.
InterruptScope::InterruptScope(std::function<bool()> poll, std::chrono::steady_clock::duration interval)
    : poll_(std::move(poll)), outer_(t_scope), interval_(interval), last_(std::chrono::steady_clock::now()) {
  if (!outer_ && g_scopes.fetch_add(1) == 0) g_flag.store(false);
  t_scope = this;
}

InterruptScope::~InterruptScope() {
  t_scope = outer_;
  if (!outer_ && g_scopes.fetch_sub(1) == 1) g_flag.store(false);
}

bool InterruptScope::due() {
  const auto now = std::chrono::steady_clock::now();
  if (now - last_ < interval_) return false;
  last_ = now;
  return poll_ && poll_();
}

void request_interrupt() {
  if (g_scopes.load() > 0) g_flag.store(true, std::memory_order_relaxed);
}

bool interrupt_flagged() { return g_flag.load(std::memory_order_relaxed); }

bool interrupt_requested() {
  if (g_flag.load(std::memory_order_relaxed)) return true;
  if (!t_scope || !t_scope->due()) return false;
  g_flag.store(true, std::memory_order_relaxed);
  return true;
}

}  // namespace granuflow
