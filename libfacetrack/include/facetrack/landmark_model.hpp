#pragma once
/// \file
/// The 2D landmark model: local binary features regression (Ren et al.,
/// "Face Alignment at 3000 FPS", CVPR 2014) with feature points kept inside
/// the current shape's padded convex hull (Shi, thesis ch. 4). Trained by
/// tools/train/landmarks; docs/landmarks.md has the details.
///
/// Like FaceModel, it is data: load it once, it is immutable, share it (by
/// shared_ptr) between any number of Trackers on any threads.

#include <cstdint>
#include <memory>
#include <string>

namespace facetrack {

namespace landmarks {
struct LbfModel;
}
namespace model {
struct Internals;
}

class LandmarkModel {
public:
    /// Throws facetrack::Error naming the file when it is missing, truncated,
    /// corrupt or of another format version.
    static std::shared_ptr<const LandmarkModel> load(const std::string& path);
    /// The shipped model: defaultPath().
    static std::shared_ptr<const LandmarkModel> loadDefault();
    /// landmarks_lbf.ftm in modelDirectory().
    static std::string defaultPath();
    static std::uint32_t formatVersion();

    int stageCount() const;
    int treesPerLandmark() const;
    int treeDepth() const;
    const std::string& sourcePath() const;

private:
    friend struct model::Internals;  // facetrack's own stages read the data behind it
    LandmarkModel(std::shared_ptr<const landmarks::LbfModel> data, std::string source);

    std::shared_ptr<const landmarks::LbfModel> data_;
    std::string source_;
};

}  // namespace facetrack
