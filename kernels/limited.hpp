// Result of a closure that may leave the paper's literal equation through a floor, cap or regularization.
// Units count `active` so a run reports how often the model was outside the equations as printed
// (docs/paper001_decisions.md: "every regularization must be reported when it becomes active").
#pragma once

namespace granuflow::kernels {

template <class T>
struct Limited {
  T value;
  bool active;  // true when the floor / cap / regularization replaced the literal value
};

// Plain comparison keeps Jets exact on either side of the kink (ceres compares the value part).
template <class T>
Limited<T> floor_at(const T& x, const T& lower) {
  return x < lower ? Limited<T>{lower, true} : Limited<T>{x, false};
}

template <class T>
Limited<T> cap_at(const T& x, const T& upper) {
  return x > upper ? Limited<T>{upper, true} : Limited<T>{x, false};
}

}  // namespace granuflow::kernels
