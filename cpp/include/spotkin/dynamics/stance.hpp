// The standing statics' status codes and the number of feet they take (statics.hpp).
#pragma once

#include <cstdint>

namespace spotkin::dynamics {

// InvalidInput is Status::InvalidInput's code, as everywhere in spotkin.
enum class Stance : std::int8_t { Ok = 0, Pulling = 1, Outside = 2, InvalidInput = 3, Unbalanced = 4 };

constexpr int kMaxFeet = 8;

}  // namespace spotkin::dynamics
