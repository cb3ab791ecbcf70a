// The guard in front of every YAML file granuflow reads (scene, sweep, experiment and stage files): size, bytes,
// UTF-8, node count with aliases expanded, depth and tags are checked before anything walks the tree
// (check_yaml_text in scene.hpp); and how a long message stays on one line (shown(), for user text inside a
// message, is in granuflow/errors.hpp).
#pragma once
#include <cstddef>
#include <string>

namespace granuflow {

// Limits that keep a hostile or mistaken file from hanging the loader or filling memory: a scene is a few
// kilobytes (an input table of 10^4 knots about 200 kB).
inline constexpr size_t kMaxSceneBytes = 1 << 20;

// Messages end up on one terminal line (exit 2 prints one line): escape what would break it, and keep a very
// long one readable.
std::string one_line(const std::string& m);

}  // namespace granuflow
