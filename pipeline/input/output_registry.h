#pragma once
/// @file
/// @brief Every name a run's outputs carry, listed from the scene before anything is computed,
/// so that a level's or a plane's name never takes the place of another output's: a points
/// column, a map's channel, a volume's grid, a footprint's layer, a file.

#include <string>
#include <vector>

#include "pipeline/input/scene.h"

namespace glint {

/// @brief One name an output will carry.
struct OutputName {
  std::string place;  ///< where it appears: "the points table's columns", "the run's files", …
  std::string name;
  std::string owner;  ///< what it holds, in words ("the aided hazard ratio")
  std::string key;    ///< the scene key that chose it (JSON pointer), empty for glint's own
};

/// @brief Every name the outputs of @p scene would carry, each with its place and owner: the
/// points table (and an engagement's), the planes' maps, the volumes, reach.exr, the reach's
/// footprint, and the files of the run's folder.
std::vector<OutputName> outputNames(const Scene& scene);

/// @brief Refuses a scene two of whose outputs would carry one name in one place (files
/// compared without regard to case, as a case-insensitive file system would), or a name longer
/// than a format can hold (OpenEXR channels: 255 bytes).
/// @throw InputError naming the key that chose the name, the name, its place and both owners.
void requireDistinctOutputNames(const Scene& scene);

}  // namespace glint
