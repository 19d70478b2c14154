#pragma once
/// \file
/// The landmark refiner of the "refine" stage: a net that reads the face aligned by LBF's
/// landmarks and moves them, before the fit, and optionally a second net that then refines the
/// brows and eyes, one side at a time. Trained by tools/train/refine (docs/landmarks.md).
///
/// Like the other models it is data: load it once, it is immutable, share it
/// (by shared_ptr) between any number of Trackers on any threads.

#include <cstdint>
#include <memory>
#include <string>

namespace facetrack {

namespace nn {
struct RefinerModelData;
}
namespace model {
struct Internals;
}

class RefinerModel {
public:
    /// Throws facetrack::Error naming the file when it is missing, truncated,
    /// corrupt or of another format version.
    static std::shared_ptr<const RefinerModel> load(const std::string& path);
    /// landmark_refiner.ftm in modelDirectory().
    static std::string defaultPath();
    static std::uint32_t formatVersion();

    const std::string& sourcePath() const;
    /// What it was trained on, as the packer wrote it.
    const std::string& provenance() const;
    /// Whether it has the brow and eye net that runs after the whole face's.
    bool hasSideNet() const;

private:
    friend struct model::Internals;  // facetrack's own stages read the data behind it
    RefinerModel(std::shared_ptr<const nn::RefinerModelData> data, std::string source);

    std::shared_ptr<const nn::RefinerModelData> data_;
    std::string source_;
};

}  // namespace facetrack
