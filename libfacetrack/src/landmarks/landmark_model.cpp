#include "facetrack/landmark_model.hpp"

#include "facetrack/error.hpp"
#include "facetrack/version.hpp"
#include "landmarks/lbf_model.hpp"
#include "model/internals.hpp"

namespace facetrack {

LandmarkModel::LandmarkModel(std::shared_ptr<const landmarks::LbfModel> data, std::string source)
    : data_(std::move(data)), source_(std::move(source)) {
    if (!data_) throw Error("LandmarkModel: null model data");
}

std::shared_ptr<const LandmarkModel> LandmarkModel::load(const std::string& path) {
    return model::Internals::make(landmarks::readLbfModel(path), path);
}

std::shared_ptr<const LandmarkModel> LandmarkModel::loadDefault() { return load(defaultPath()); }
std::string LandmarkModel::defaultPath() { return modelDirectory() + "/landmarks_lbf.ftm"; }

std::uint32_t LandmarkModel::formatVersion() { return landmarks::kLbfVersion; }
int LandmarkModel::stageCount() const { return static_cast<int>(data_->stages.size()); }
int LandmarkModel::treesPerLandmark() const { return data_->trees_per_landmark; }
int LandmarkModel::treeDepth() const { return data_->tree_depth; }
const std::string& LandmarkModel::sourcePath() const { return source_; }

}  // namespace facetrack
