#pragma once
/// \file
/// The eye model of the gaze stage (Wang, Shi, Xia, Chai 2016): random forests
/// over pixel tests on a normalised eye patch, one classifying each pixel as
/// skin, sclera or iris, one regressing the eyelid aperture. Trained by
/// tools/train/eyes on MediaPipe teacher labels (models/README.md, docs/gaze.md).
///
/// Like the other models it is data: load it once, it is immutable, share it
/// (by shared_ptr) between any number of Trackers on any threads.

#include <cstdint>
#include <memory>
#include <string>

namespace facetrack {

namespace gaze {
struct EyeModelData;
}
namespace model {
struct Internals;
}

class EyeModel {
public:
    /// Throws facetrack::Error naming the file when it is missing, truncated,
    /// corrupt or of another format version.
    static std::shared_ptr<const EyeModel> load(const std::string& path);
    /// The shipped model: defaultPath().
    static std::shared_ptr<const EyeModel> loadDefault();
    /// eye_model.ftm in modelDirectory().
    static std::string defaultPath();
    static std::uint32_t formatVersion();

    const std::string& sourcePath() const;
    /// What it was trained on, as the trainer wrote it.
    const std::string& provenance() const;

private:
    friend struct model::Internals;  // facetrack's own stages read the data behind it
    EyeModel(std::shared_ptr<const gaze::EyeModelData> data, std::string source);

    std::shared_ptr<const gaze::EyeModelData> data_;
    std::string source_;
};

}  // namespace facetrack
