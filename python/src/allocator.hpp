// The allocator policy of a process that imports granuflow._core (allocator.cpp says why and what).
#pragma once
#include <string>

namespace granuflow::python {

// Keeps freed blocks for the next solve (glibc only; nothing when the user configured malloc in the environment).
// Returns a warning for a GRANUFLOW_MALLOC_TUNING other than 0 or 1 (then nothing is changed), else "".
std::string tune_allocator();
// Whether tune_allocator() changed the allocator's thresholds in this process.
bool allocator_tuned();

}  // namespace granuflow::python
