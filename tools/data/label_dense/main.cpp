// label_dense: dense teacher labels (docs/expressions.md). Fits the face model's
// pose, identity and every expression but the eyeballs' looks to MediaPipe's
// 478-point mesh of every 300-W crop and clip frame (../shared/data/teacher,
// another model's predictions, not ground truth), through a correspondence
// between MediaPipe's vertices and the model's surface and a learned teacher
// convention (docs/expressions.md). Writes
//   OUT/correspondence.csv   MediaPipe vertex -> model triangle, barycentric weights, distance
//   OUT/faces300w.csv        one row per crop: split, residual, pose, identity, expression weights
//   OUT/clips.csv            one row per clip frame (identity shared per clip)
//   OUT/summary.json         the checks and figures printed here (summary_300w.json with --only 300w, ...)
//
//   build/tools/label_dense [--out build/dense_labels] [--only 300w|clips] [--limit N]
// (--only 300w and --only clips in two processes use both cores.)

#include "app/args.hpp"
#include "app/tool_main.hpp"
#include "common/faces300w.hpp"
#include "core/pts.hpp"
#include "data/dense/correspondence.hpp"
#include "data/dense/dense_fit.hpp"
#include "data/dense/mediapipe_mesh.hpp"
#include "facetrack/face_model.hpp"
#include "fit/face_fitter.hpp"
#include "model/internals.hpp"
#include "model/landmark_convention.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <numeric>

using namespace facetrack;

namespace {

/// The clips the gaze and CNN evaluations hold out (docs/gaze.md): never trained on.
constexpr const char* kHeldOutClips[] = {"liveportrait_d14_gaze_shifts.mp4", "fgnet_talking_face_franck.mp4"};

double seconds() {
    static const auto start = std::chrono::steady_clock::now();
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void progress(const char* what, int done, int total) {
    if (done % 100 != 0 && done != total) return;
    const double t = seconds();
    std::fprintf(stderr, "\r%s: %d / %d (%.0f s)   ", what, done, total, t);
    if (done == total) std::fputc('\n', stderr);
}

double quantile(std::vector<double> v, double q) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1))];
}

/// Split of each 300-W image, by its path relative to the faces300w folder.
std::map<std::string, std::string> splitsOf300W(const std::string& root) {
    std::map<std::string, std::string> out;
    for (const auto& [split, name] :
         {std::pair{tools::Split::Train, "train"}, {tools::Split::Validation, "validation"}, {tools::Split::Test, "test"}}) {
        for (const auto& a : tools::list300W(root, split)) out[std::filesystem::relative(a.image, root).string()] = name;
    }
    return out;
}

void writeHeader(std::ofstream& out, const std::vector<std::string>& names, int identities) {
    out << "key,split,residual,pitch_deg,yaw_deg,roll_deg,omega_x,omega_y,omega_z,t_x_cm,t_y_cm,t_z_cm";
    for (int k = 0; k < identities; ++k) out << ",id" << k;
    for (const auto& n : names) out << ',' << n;
    out << '\n';
}

void writeRow(std::ofstream& out, const std::string& key, const std::string& split, const dense::DenseFrame& f,
              const Eigen::VectorXd& identity) {
    const Eigen::Vector3d euler = fit::eulerDegrees(f.params.omega());
    char buf[64];
    out << key << ',' << split;
    auto put = [&](double v, const char* format) {
        std::snprintf(buf, sizeof buf, format, v);
        out << ',' << buf;
    };
    put(f.residual, "%.5f");
    for (int c = 0; c < 3; ++c) put(euler[c], "%.3f");
    for (int c = 0; c < 6; ++c) put(f.params.pose[c], "%.5f");
    for (Eigen::Index k = 0; k < identity.size(); ++k) put(identity[k], "%.4f");
    for (Eigen::Index k = 0; k < f.params.expression.size(); ++k) put(f.params.expression[k], "%.4f");
    out << '\n';
}

/// NME (inter-ocular, points 17-67) of the dense fit's 68 landmarks, placed with the learned
/// convention, against the 300-W annotation: how well the labels agree with human annotators.
struct LandmarkCheck {
    fit::PointBasis basis;
    explicit LandmarkCheck(const model::FaceModelData& data, const model::LandmarkConvention& convention,
                           const std::vector<int>& expressions) {
        std::vector<fit::SurfacePoint> points(model::kLandmarkCount);
        for (int i = 0; i < model::kLandmarkCount; ++i) {
            const auto v = data.landmark_vertices[static_cast<std::size_t>(i)];
            points[static_cast<std::size_t>(i)].vertices = {v, v, v};
        }
        basis = fit::buildPointBasis(data, points, expressions);
        basis.neutral += convention.offsets_frontal_cm;
    }
    /// Per region (brows 17-26, nose 27-35, eyes 36-47, mouth 48-67) and over all of 17-67.
    std::array<double, 5> nme(const dense::DenseFrame& f, const Eigen::VectorXd& identity, const core::Shape2& truth) const {
        dense::DenseModel m{basis, {}, {36, 45}};
        const Eigen::Matrix2Xd p = dense::projectPoints(m, identity, f.camera, f.params);
        const double iod = (truth.col(36) - truth.col(45)).cast<double>().norm();
        std::array<double, 5> sum{};
        std::array<int, 5> count{};
        for (int i = model::kContourLandmarkCount; i < model::kLandmarkCount; ++i) {
            const int region = i < 27 ? 0 : i < 36 ? 1 : i < 48 ? 2 : 3;
            const double e = (p.col(i) - truth.col(i).cast<double>()).norm() / iod;
            for (const int r : {region, 4}) {
                sum[static_cast<std::size_t>(r)] += e;
                ++count[static_cast<std::size_t>(r)];
            }
        }
        for (std::size_t r = 0; r < 5; ++r) sum[r] /= count[r];
        return sum;
    }
};

/// What every labelling step shares.
struct Setup {
    const model::FaceModelData& data;
    dense::Correspondence correspondence;
    dense::CanonicalMesh canonical;
    std::vector<int> vertices;  ///< the MediaPipe vertex of each slot
    dense::DenseModel model;
    dense::DenseFitSettings settings;
    std::vector<std::string> names;  ///< the fitted expressions
};

/// The teacher's convention (dense::learnTeacherConvention), learned on the 300-W training crops
/// whose annotated landmarks fit a closed, unsmiling mouth: 300-W's average face smiles, and a
/// convention learned on it would read a relaxed mouth as its opposite. Added to s.model.
void learnConvention(Setup& s, const dense::TeacherMeshes& faces, const std::map<std::string, std::string>& splits, const std::string& root,
                     int rounds, nlohmann::json& summary) {
    const auto& data = s.data;
    const auto& vertices = s.vertices;
    // The landmark convention's offsets with a flat prior: its prior is learned from these labels.
    fit::FitBasis offsetsOnly = *fit::basisOf(FaceModel::loadDefault());
    offsetsOnly.expression_prior.setOnes();
    const auto tracked = std::make_shared<const fit::FitBasis>(std::move(offsetsOnly));
    fit::FaceFitter fitter(tracked, fit::FitSettings());
    const auto fitted = tracked->expressionNames(data);
    std::vector<int> mouth;
    for (const char* name : {"jawOpen", "mouthSmile_L", "mouthSmile_R"})
        mouth.push_back(static_cast<int>(std::find(fitted.begin(), fitted.end(), name) - fitted.begin()));
    std::vector<dense::DenseFrame> train;
    int candidates = 0;
    for (int r = 0; r < faces.rows(); ++r) {
        const std::string& key = faces.keys[static_cast<std::size_t>(r)];
        const auto split = splits.find(key);
        if (!faces.found[static_cast<std::size_t>(r)] || split == splits.end() || split->second != "train") continue;
        ++candidates;
        const core::Shape2 pts = core::readPts((std::filesystem::path(root) / key).replace_extension(".pts").string());
        fit::FaceParams p;
        fitter.fit(dense::teacherFrame(faces, r, vertices).camera, pts.cast<double>(), p, false);
        if (std::all_of(mouth.begin(), mouth.end(), [&](int k) { return k < p.expression.size() && p.expression[k] < 0.1; }))
            train.push_back(dense::teacherFrame(faces, r, vertices));
    }
    std::printf("teacher convention: %zu of %d training crops fit a closed, unsmiling mouth\n", train.size(), candidates);
    const std::vector<int> mirrorOf = dense::mirrorVertices(s.canonical.vertices);
    std::vector<int> mirrorSlot(vertices.size());
    for (std::size_t s = 0; s < vertices.size(); ++s) {
        const auto it = std::find(vertices.begin(), vertices.end(), mirrorOf[static_cast<std::size_t>(vertices[s])]);
        mirrorSlot[s] = it == vertices.end() ? static_cast<int>(s) : static_cast<int>(it - vertices.begin());
    }
    const Eigen::Matrix3Xd offsets = dense::learnTeacherConvention(s.model, s.settings, train, mirrorSlot, rounds);
    std::vector<double> mm;
    for (Eigen::Index i = 0; i < offsets.cols(); ++i) mm.push_back(10.0 * offsets.col(i).norm());
    std::printf("teacher convention (%zu training crops, %d rounds): offsets median %.2f mm, p90 %.2f mm, max %.2f mm\n", train.size(),
                rounds, quantile(mm, 0.5), quantile(mm, 0.9), quantile(mm, 1.0));
    summary["teacher_convention"] = {{"crops", train.size()}, {"median_mm", quantile(mm, 0.5)}, {"p90_mm", quantile(mm, 0.9)}};
    std::vector<dense::DenseFrame> one{dense::canonicalFrame(s.correspondence, s.canonical.vertices, vertices, 0.0)};
    dense::fitIdentity(s.model, s.settings, one);
    Eigen::Index worst = 0;
    const double largest = one[0].params.expression.maxCoeff(&worst);
    std::printf("canonical neutral with the teacher convention, fitted identity: largest expression %s %.3f, mean %.4f\n",
                s.names[static_cast<std::size_t>(worst)].c_str(), largest, one[0].params.expression.mean());
    summary["canonical_check_with_convention"] = {{"largest", largest}, {"largest_name", s.names[static_cast<std::size_t>(worst)]}};
}

/// Labels every 300-W crop: one view each, so identity is fitted per image. Writes faces300w.csv.
void label300W(const Setup& s, const dense::TeacherMeshes& meshes, const std::map<std::string, std::string>& splits,
               const std::string& root, const std::string& outDir, int limit, nlohmann::json& summary) {
    const auto conventionData = model::readLandmarkConvention(FaceModel::defaultConventionPath());
    const LandmarkCheck landmarkCheck(s.data, conventionData, s.model.basis.expressions);
    const auto& vertices = s.vertices;
    std::ofstream out(outDir + "/faces300w.csv");
    writeHeader(out, s.names, s.model.basis.identityCount());
    std::map<std::string, std::vector<double>> residuals;
    std::map<std::string, std::array<std::vector<double>, 5>> nmes;
    const int total = std::min(meshes.rows(), limit);
    for (int r = 0; r < total; ++r) {
        progress("300-W", r + 1, total);
        if (!meshes.found[static_cast<std::size_t>(r)]) continue;
        const std::string& key = meshes.keys[static_cast<std::size_t>(r)];
        const auto split = splits.find(key);
        const std::string splitName = split == splits.end() ? "other" : split->second;
        std::vector<dense::DenseFrame> one{dense::teacherFrame(meshes, r, vertices)};
        const Eigen::VectorXd identity = dense::fitIdentity(s.model, s.settings, one);
        writeRow(out, key, splitName, one[0], identity);
        residuals[splitName].push_back(one[0].residual);
        const std::string pts = (std::filesystem::path(root) / key).replace_extension(".pts").string();
        if (std::filesystem::exists(pts)) {
            const auto e = landmarkCheck.nme(one[0], identity, core::readPts(pts));
            for (std::size_t g = 0; g < e.size(); ++g) nmes[splitName][g].push_back(e[g]);
        }
    }
    for (const auto& [split, v] : residuals) {
        const auto& n = nmes[split];
        std::printf(
            "300-W %-10s %4zu crops: residual to the teacher median %.4f, p95 %.4f eye-corner distances\n"
            "  landmarks vs the annotation, median NME (inter-ocular): brows %.4f, nose %.4f, eyes %.4f, mouth %.4f, "
            "17-67 %.4f\n",
            split.c_str(), v.size(), quantile(v, 0.5), quantile(v, 0.95), quantile(n[0], 0.5), quantile(n[1], 0.5), quantile(n[2], 0.5),
            quantile(n[3], 0.5), quantile(n[4], 0.5));
        summary["faces300w"][split] = {{"crops", v.size()},
                                       {"residual_median", quantile(v, 0.5)},
                                       {"residual_p95", quantile(v, 0.95)},
                                       {"landmark_nme_median", quantile(n[4], 0.5)}};
    }
}

/// Labels every clip frame: identity shared per clip (fitted on 40 frames spread over it), then
/// every frame, warm from the previous one. Writes clips.csv.
void labelClips(const Setup& s, const std::string& teacherDir, const std::string& outDir, int limit, nlohmann::json& summary) {
    const auto& vertices = s.vertices;
    const auto meshes = dense::readTeacherMeshes(teacherDir + "/clips_iris.jsonl", teacherDir + "/clips_mesh.npy");
    std::map<std::string, std::vector<int>> rowsOf;
    for (int r = 0; r < meshes.rows(); ++r) {
        if (!meshes.found[static_cast<std::size_t>(r)]) continue;
        const std::string& key = meshes.keys[static_cast<std::size_t>(r)];
        rowsOf[key.substr(0, key.rfind('#'))].push_back(r);
    }
    std::ofstream out(outDir + "/clips.csv");
    writeHeader(out, s.names, s.model.basis.identityCount());
    auto frameOf = [&](int r) { return dense::teacherFrame(meshes, r, vertices); };
    int done = 0, total = 0;
    for (const auto& [clip, rows] : rowsOf) total += std::min(static_cast<int>(rows.size()), limit);
    for (const auto& [clip, rows] : rowsOf) {
        const bool heldOut = std::find(std::begin(kHeldOutClips), std::end(kHeldOutClips), clip) != std::end(kHeldOutClips);
        const int count = std::min(static_cast<int>(rows.size()), limit);
        std::vector<dense::DenseFrame> sample;
        for (int k = 0; k < 40; ++k) sample.push_back(frameOf(rows[static_cast<std::size_t>(k * (count - 1) / 39)]));
        const Eigen::VectorXd identity = dense::fitIdentity(s.model, s.settings, sample);
        std::vector<double> residuals;
        dense::DenseFrame previous;
        for (int k = 0; k < count; ++k) {
            progress("clips", ++done, total);
            dense::DenseFrame f = frameOf(rows[static_cast<std::size_t>(k)]);
            f.params = previous.params;
            dense::fitFrame(s.model, s.settings, identity, f, k > 0 && previous.residual < 0.1);
            writeRow(out, meshes.keys[static_cast<std::size_t>(rows[static_cast<std::size_t>(k)])], heldOut ? "heldout" : "train", f,
                     identity);
            residuals.push_back(f.residual);
            previous = f;
        }
        std::printf("clip %-42s %4d frames: residual median %.4f, p95 %.4f; |identity| %.2f\n", clip.c_str(), count,
                    quantile(residuals, 0.5), quantile(residuals, 0.95), identity.norm());
        summary["clips"][clip] = {{"frames", count},
                                  {"residual_median", quantile(residuals, 0.5)},
                                  {"residual_p95", quantile(residuals, 0.95)},
                                  {"split", heldOut ? "heldout" : "train"}};
    }
}

int run(int argc, char** argv) {
    const tools::Args args(std::vector<std::string>(argv + 1, argv + argc),
                           {"--out", "--only", "--limit", "--teacher", "--canonical", "--faces300w", "--identity-prior", "--observable-l2",
                            "--unobservable-l2", "--convention-rounds"},
                           {"--help"});
    if (args.has("--help")) {
        std::puts(
            "usage: label_dense [--out build/dense_labels] [--only 300w|clips] [--limit N] [--teacher DIR]\n"
            "                   [--canonical OBJ] [--faces300w DIR]");
        return 0;
    }
    std::setvbuf(stdout, nullptr, _IOLBF, 0);  // the log shows each step as it ends
    const std::string teacherDir = args.get("--teacher", "../shared/data/teacher");
    const std::string outDir = args.get("--out", "build/dense_labels");
    const std::string only = args.get("--only", "");
    const int limit = args.integer("--limit", 1000000000);
    std::filesystem::create_directories(outDir);
    nlohmann::json summary;

    const auto model = FaceModel::load(FaceModel::defaultPath());
    const model::FaceModelData& data = model::dataOf(*model);
    const auto canonical = dense::readCanonicalMesh(
        args.get("--canonical", "../shared/models/mediapipe-canonical/canonical_face_model.obj"));

    // 1. Correspondence.
    const dense::Correspondence corr = dense::buildCorrespondence(data, canonical.vertices);
    {
        std::ofstream out(outDir + "/correspondence.csv");
        out << "mediapipe_vertex,v0,v1,v2,w0,w1,w2,distance_cm,used\n";
        for (int i = 0; i < dense::kMeshVertexCount; ++i) {
            const auto& p = corr.points[static_cast<std::size_t>(i)];
            out << i << ',' << p.vertices[0] << ',' << p.vertices[1] << ',' << p.vertices[2] << ',' << p.weights[0] << ',' << p.weights[1]
                << ',' << p.weights[2] << ',' << corr.distance_cm[static_cast<std::size_t>(i)] << ','
                << int(corr.usable[static_cast<std::size_t>(i)]) << '\n';
        }
    }
    const double medianDistance = quantile(corr.distance_cm, 0.5), p90Distance = quantile(corr.distance_cm, 0.9);
    {
        const Eigen::AngleAxisd turn(corr.rotation);
        std::printf("alignment rotation %.2f deg about (%.2f, %.2f, %.2f)\n", turn.angle() * 180 / M_PI, turn.axis().x(), turn.axis().y(),
                    turn.axis().z());
    }
    std::printf(
        "correspondence: %d of %d MediaPipe vertices on the model's face (< %.1f mm); distance median %.2f mm, p90 %.2f mm; "
        "scale %.3f, |identity| %.2f\n",
        corr.usableCount(), dense::kMeshVertexCount, 10 * dense::kMaxDistanceCm, 10 * medianDistance, 10 * p90Distance, corr.scale,
        corr.identity.norm());
    summary["correspondence"] = {
        {"used", corr.usableCount()}, {"median_mm", 10 * medianDistance}, {"p90_mm", 10 * p90Distance}, {"scale", corr.scale}};

    // 2. Which expressions the dense points observe (the landmark fit's rule). The labels fit all of
    // them but eyeLook* (the mesh has no eyeballs): the prior settles what the points cannot.
    const std::vector<int> vertices = corr.usableVertices();
    std::vector<fit::SurfacePoint> points;
    for (const int v : vertices) points.push_back(corr.points[static_cast<std::size_t>(v)]);
    const std::vector<int> observable = fit::observableExpressions(data, points);
    const std::vector<int> candidates = dense::labelledExpressions(data);
    dense::DenseModel dm = dense::denseModel(data, corr, candidates);
    const std::vector<std::string> names = dm.basis.expressionNames(data);
    std::vector<std::string> observableNames;
    for (const int e : observable) observableNames.push_back(data.expressions[static_cast<std::size_t>(e)].name);
    const auto landmarkNames = fit::basisOf(model)->expressionNames(data);
    std::printf("fitted: %zu expressions; observable from the dense points: %zu (68 landmarks: %zu)\n  ", names.size(),
                observableNames.size(), landmarkNames.size());
    for (const auto& n : observableNames) {
        const bool byLandmarks = std::find(landmarkNames.begin(), landmarkNames.end(), n) != landmarkNames.end();
        std::printf("%s%s ", n.c_str(), byLandmarks ? "" : "*");
    }
    std::printf("\n  (* = not observable from the 68 landmarks)\n");
    {
        // Each candidate's distinct motion among all candidates: why the others were dropped.
        const auto motion = fit::distinctMotion(data, points, candidates);
        const auto kept = fit::distinctMotion(data, points, observable);
        std::printf("  distinct motion (eye-corner distances per unit weight; threshold 0.08), among all candidates -> among the kept:\n");
        for (std::size_t k = 0; k < candidates.size(); ++k) {
            const auto it = std::find(observable.begin(), observable.end(), candidates[k]);
            const std::string& name = data.expressions[static_cast<std::size_t>(candidates[k])].name;
            if (it == observable.end()) {
                std::printf("    %-18s %.3f  dropped\n", name.c_str(), motion[k]);
            } else {
                std::printf("    %-18s %.3f -> %.3f\n", name.c_str(), motion[k], kept[static_cast<std::size_t>(it - observable.begin())]);
            }
        }
    }
    summary["fitted"] = names;
    summary["observable"] = observableNames;
    summary["observable_by_landmarks"] = landmarkNames;

    // 3. Check: the canonical neutral face fits no expression, frontal and turned: with its own
    // identity (the correspondence's), and with the identity fitted from this one view.
    dense::DenseFitSettings settings;
    settings.identity_prior = args.number("--identity-prior", settings.identity_prior);
    settings.observable_l2 = args.number("--observable-l2", settings.observable_l2);
    settings.unobservable_l2 = args.number("--unobservable-l2", settings.unobservable_l2);
    for (const double yaw : {0.0, 30.0}) {
        for (const bool ownIdentity : {true, false}) {
            std::vector<dense::DenseFrame> one{dense::canonicalFrame(corr, canonical.vertices, vertices, yaw)};
            if (ownIdentity) {
                dense::fitFrame(dm, settings, corr.identity, one[0], false);
            } else {
                dense::fitIdentity(dm, settings, one);
            }
            const Eigen::VectorXd& b = one[0].params.expression;
            Eigen::Index worst = 0;
            const double largest = b.maxCoeff(&worst);
            std::printf("canonical neutral at yaw %2.0f, %s identity: residual %.4f, largest expression %s %.3f, mean %.4f\n", yaw,
                        ownIdentity ? "its own" : "fitted", one[0].residual, names[static_cast<std::size_t>(worst)].c_str(), largest,
                        b.mean());
            summary["canonical_check"].push_back({{"yaw", yaw},
                                                  {"identity", ownIdentity ? "own" : "fitted"},
                                                  {"largest", largest},
                                                  {"largest_name", names[static_cast<std::size_t>(worst)]},
                                                  {"mean", b.mean()}});
        }
    }

    Setup s{data, corr, canonical, vertices, dm, settings, names};
    const std::string root = tools::faces300wRoot(args.get("--faces300w", ""));
    const auto splits = splitsOf300W(root);
    const auto faces = dense::readTeacherMeshes(teacherDir + "/faces300w_iris.jsonl", teacherDir + "/faces300w_mesh.npy");
    learnConvention(s, faces, splits, root, args.integer("--convention-rounds", 3), summary);
    if (only.empty() || only == "300w") label300W(s, faces, splits, root, outDir, limit, summary);
    if (only.empty() || only == "clips") labelClips(s, teacherDir, outDir, limit, summary);
    const std::string summaryPath = outDir + "/summary" + (only.empty() ? "" : "_" + only) + ".json";
    std::ofstream(summaryPath) << summary.dump(2) << '\n';
    std::printf("wrote %s/{correspondence,faces300w,clips}.csv and %s (%.0f s)\n", outDir.c_str(), summaryPath.c_str(), seconds());
    return 0;
}

}  // namespace

int main(int argc, char** argv) { return tools::runTool("label_dense", run, argc, argv); }
