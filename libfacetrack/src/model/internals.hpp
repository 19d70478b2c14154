#pragma once
// The data behind the public model classes (FaceModel, LandmarkModel,
// RefinerModel, EyeModel, CnnModel), for facetrack's own stages and tools. The public
// headers name no internal type but the pointers they hold and this friend.
// Every model is made here, from the data its reader returns: one way to
// turn a file into a shared, immutable model.

#include "facetrack/cnn_model.hpp"
#include "facetrack/eye_model.hpp"
#include "facetrack/face_model.hpp"
#include "facetrack/landmark_model.hpp"
#include "facetrack/refiner_model.hpp"

#include <memory>
#include <string>
#include <utility>

namespace facetrack::model {

struct Internals {
    static const FaceModelData& data(const FaceModel& m) { return *m.data_; }
    /// Null when the model was loaded without a landmark convention.
    static const LandmarkConvention* convention(const FaceModel& m) { return m.landmark_convention_.get(); }
    static const landmarks::LbfModel& data(const LandmarkModel& m) { return *m.data_; }
    static const gaze::EyeModelData& data(const EyeModel& m) { return *m.data_; }
    static const nn::CnnModelData& data(const CnnModel& m) { return *m.data_; }
    static const nn::RefinerModelData& data(const RefinerModel& m) { return *m.data_; }

    /// The model of `data` (a reader's result, or data a tool built), read from
    /// `source`; `Data` picks the model class.
    template <class Data, class... Extra>
    static auto make(Data data, std::string source, Extra&&... extra) {
        using Model = typename ModelOf<Data>::type;
        auto shared = std::make_shared<const Data>(std::move(data));
        return std::shared_ptr<const Model>(new Model(std::move(shared), std::move(source), std::forward<Extra>(extra)...));
    }

private:
    template <class Data>
    struct ModelOf;
};

template <>
struct Internals::ModelOf<FaceModelData> {
    using type = FaceModel;
};
template <>
struct Internals::ModelOf<landmarks::LbfModel> {
    using type = LandmarkModel;
};
template <>
struct Internals::ModelOf<gaze::EyeModelData> {
    using type = EyeModel;
};
template <>
struct Internals::ModelOf<nn::CnnModelData> {
    using type = CnnModel;
};
template <>
struct Internals::ModelOf<nn::RefinerModelData> {
    using type = RefinerModel;
};

/// The data behind a model: dataOf(*face), dataOf(*cascade), ...
template <class Model>
const auto& dataOf(const Model& m) {
    return Internals::data(m);
}

}  // namespace facetrack::model
