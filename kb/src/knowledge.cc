#include "insdiag/kb/knowledge.h"

namespace insdiag::kb {

const char* ScaleName(Scale scale) {
  switch (scale) {
    case Scale::kLogRatio: return "log_ratio";
    case Scale::kTolerance: return "tolerance";
    case Scale::kZ: return "z";
  }
  return "";
}

std::optional<Scale> ScaleNamed(std::string_view name) {
  for (Scale scale : {Scale::kLogRatio, Scale::kTolerance, Scale::kZ}) {
    if (name == ScaleName(scale)) return scale;
  }
  return std::nullopt;
}

const char* DirectionName(Direction direction) {
  switch (direction) {
    case Direction::kUp: return "UP";
    case Direction::kDown: return "DOWN";
    case Direction::kEither: return "EITHER";
  }
  return "";
}

std::optional<Direction> DirectionNamed(std::string_view name) {
  for (Direction direction : {Direction::kUp, Direction::kDown, Direction::kEither}) {
    if (name == DirectionName(direction)) return direction;
  }
  return std::nullopt;
}

}  // namespace insdiag::kb
