// Recordings as datasets (io/datasets/recording_source.h, docs/RECORDINGS.md): a synthetic room written as a
// TUM folder, then as every recording vkmesh reads (tests/support/make_recordings.py: ROS 1 bags in TUM's
// layout uncompressed, bz2 and lz4, MCAP uncompressed, zstd and lz4, a rosbag2 .db3, a RealSense bag). Each
// must give exactly the folder's frames: depth, colour, poses and calibration; the topic options choose and
// name what they choose; recordings vkmesh cannot use are refused naming the file and what is wrong.
#include "io/dataset.h"
#include "synth/synthetic_scene.h"
#include "synth/tum_sequence.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <fstream>

namespace fs = std::filesystem;
using namespace vkmesh;

namespace {

const char* kTumKinds[] = {"tum-ros1-none", "tum-ros1-bz2", "tum-ros1-lz4", "tum-mcap-none",
                           "tum-mcap-zstd", "tum-mcap-lz4", "tum-db3"};

fs::path recordingPath(const fs::path& dir, const std::string& kind) {
    if (kind == "realsense") return dir / "realsense.bag";
    if (kind.find("ros1") != std::string::npos) return dir / (kind + ".bag");
    if (kind.find("mcap") != std::string::npos) return dir / (kind + ".mcap");
    return dir / kind;
}

class RecordingDatasets : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        root_ = new fs::path(test::makeTempDir("recording_datasets"));
        synth::SequenceOptions o;
        o.frames = 6;
        o.width = 160;
        o.height = 120;
        o.intrinsics = synth::kinectIntrinsics(160, 120);
        o.noise = true;   // zeros (dropouts) in the depth: NaN in the 32FC1 bags
        o.gtPointSpacing = 0.05;   // not compared here; the default 5 mm took most of the suite's time under ASan
        synth::writeTumSequence(*root_ / "room", synth::SyntheticScene::defaultRoom(), o);
        std::string kinds;
        for (const char* k : kTumKinds) kinds += std::string(k) + ",";
        *skip_ = test::makeRecordings(*root_ / "room", *root_ / "recordings", kinds + "realsense");
    }
    static void TearDownTestSuite() {
        fs::remove_all(*root_);
        delete root_;
    }
    void SetUp() override {
        if (!skip_->empty()) GTEST_SKIP() << *skip_;
    }
    static fs::path folder() { return *root_ / "room"; }
    static fs::path recording(const std::string& kind) { return recordingPath(*root_ / "recordings", kind); }

    static fs::path* root_;
    static std::string* skip_;
};
fs::path* RecordingDatasets::root_ = nullptr;
std::string* RecordingDatasets::skip_ = new std::string;

void expectSameFrames(const Dataset& folder, const Dataset& rec, bool poses, const std::string& what) {
    ASSERT_EQ(rec.size(), folder.size()) << what;
    EXPECT_EQ(rec.intrinsics().fx, folder.intrinsics().fx) << what;
    EXPECT_EQ(rec.intrinsics().fy, folder.intrinsics().fy) << what;
    EXPECT_EQ(rec.intrinsics().cx, folder.intrinsics().cx) << what;
    EXPECT_EQ(rec.intrinsics().cy, folder.intrinsics().cy) << what;
    EXPECT_EQ(rec.intrinsics().width, folder.intrinsics().width) << what;
    EXPECT_EQ(rec.intrinsics().height, folder.intrinsics().height) << what;
    EXPECT_TRUE(rec.hasColor()) << what;
    EXPECT_EQ(rec.hasPoses(), poses) << what;
    for (size_t i = 0; i < folder.size(); ++i) {
        EXPECT_EQ(rec.loadDepth(i).meters, folder.loadDepth(i).meters) << what << " frame " << i;
        std::string warning;
        EXPECT_EQ(rec.loadColor(i, &warning).rgb, folder.loadColor(i).rgb) << what << " frame " << i << " " << warning;
        EXPECT_NEAR(rec.frame(i).timestamp, folder.frame(i).timestamp, 1e-6) << what << " frame " << i;
        EXPECT_FALSE(rec.frame(i).depthRecord.empty()) << what;
        if (poses) {
            EXPECT_TRUE(rec.frame(i).hasPose) << what << " frame " << i;
            EXPECT_EQ(rec.frame(i).cameraToWorld, folder.frame(i).cameraToWorld) << what << " frame " << i;
        }
    }
}

}  // namespace

TEST_F(RecordingDatasets, EveryContainerGivesTheFolderFramesExactly) {
    const auto f = Dataset::open(folder());
    for (const char* kind : kTumKinds) {
        SCOPED_TRACE(kind);
        const auto r = Dataset::open(recording(kind));
        EXPECT_EQ(r->kind(), std::string(kind).find("ros1") != std::string::npos   ? DatasetKind::RosBag
                             : std::string(kind).find("mcap") != std::string::npos ? DatasetKind::Mcap
                                                                                   : DatasetKind::Rosbag2);
        EXPECT_NE(r->description().find("/camera/depth/image (32FC1)"), std::string::npos) << r->description();
        EXPECT_NE(r->description().find("/camera/rgb/image_color"), std::string::npos) << r->description();
        expectSameFrames(*f, *r, true, kind);
    }
}

TEST_F(RecordingDatasets, RealSenseLayoutReadsItsDepthUnitsAndNeedsTracking) {
    // A RealSense recording has no poses: refused with the way out, opened for tracking.
    const std::string refused = test::errorMessageOf([&] { Dataset::open(recording("realsense")); });
    EXPECT_NE(refused.find("realsense.bag"), std::string::npos) << refused;
    EXPECT_NE(refused.find("--track"), std::string::npos) << refused;
    DatasetOptions options;
    options.requirePoses = false;
    const auto r = Dataset::open(recording("realsense"), options);
    const auto f = Dataset::open(folder(), options);
    EXPECT_EQ(r->kind(), DatasetKind::RealSenseBag);
    // Depth Units 0.0002 as a float is 1/4999.99987: read as the 5000 units per metre it stands for.
    EXPECT_EQ(r->depthScale(), 5000.0);
    expectSameFrames(*f, *r, false, "realsense");
    // The colour stream's lens distortion is not undone, and the user is told (the depth stream's is zero).
    std::string warnings;
    for (const std::string& w : r->warnings()) warnings += w + "\n";
    EXPECT_NE(warnings.find("Color_0/info/camera_info"), std::string::npos) << warnings;
    EXPECT_NE(warnings.find("colour camera has lens distortion (Inverse Brown Conrady)"), std::string::npos) << warnings;
    EXPECT_EQ(warnings.find("depth camera has lens distortion"), std::string::npos) << warnings;
}

TEST_F(RecordingDatasets, TopicOptionsChooseAndNameWhatIsThere) {
    DatasetOptions options;
    options.depthTopic = "/camera/depth/nothing";
    std::string message = test::errorMessageOf([&] { Dataset::open(recording("tum-mcap-zstd"), options); });
    EXPECT_NE(message.find("--depth-topic /camera/depth/nothing"), std::string::npos) << message;
    EXPECT_NE(message.find("/camera/depth/image (32FC1"), std::string::npos) << message;   // lists what there is

    options = {};
    options.colorTopic = "/camera/depth/image";
    message = test::errorMessageOf([&] { Dataset::open(recording("tum-ros1-none"), options); });
    EXPECT_NE(message.find("/camera/depth/image"), std::string::npos) << message;

    options = {};
    options.infoTopic = "/camera/ir/camera_info";
    message = test::errorMessageOf([&] { Dataset::open(recording("tum-db3"), options); });
    EXPECT_NE(message.find("--info-topic"), std::string::npos) << message;
    EXPECT_NE(message.find("/camera/depth/camera_info"), std::string::npos) << message;

    // Naming the topics the defaults would choose gives the same dataset.
    options = {};
    options.depthTopic = "/camera/depth/image";
    options.colorTopic = "/camera/rgb/image_color";
    options.infoTopic = "/camera/depth/camera_info";
    expectSameFrames(*Dataset::open(folder()), *Dataset::open(recording("tum-ros1-lz4"), options), true, "named topics");
}

TEST_F(RecordingDatasets, TruncatedAndForeignFilesAreRefusedNamingTheFile) {
    const fs::path dir = test::makeTempDir("recording_hostile");
    for (const char* kind : {"tum-ros1-bz2", "tum-mcap-zstd"}) {
        const std::string bytes = test::readText(recording(kind));
        for (double keep : {0.5, 0.9}) {
            const fs::path cut = dir / (std::string("cut_") + std::to_string(int(keep * 100)) + "_" + recording(kind).filename().string());
            test::writeBytes(cut, bytes.substr(0, size_t(double(bytes.size()) * keep)));
            // Either refused, naming the file, or (a recording cut between records) opened with fewer frames:
            // never a crash, never a frame that is not the folder's.
            try {
                const auto r = Dataset::open(cut);
                const auto f = Dataset::open(folder());
                ASSERT_LE(r->size(), f->size());
                for (size_t i = 0; i < r->size(); ++i) {
                    try {
                        EXPECT_EQ(r->loadDepth(i).meters, f->loadDepth(i).meters) << cut << " frame " << i;
                    } catch (const Error& e) {
                        EXPECT_NE(std::string(e.what()).find(cut.filename().string()), std::string::npos) << e.what();
                    }
                }
            } catch (const Error& e) {
                EXPECT_NE(std::string(e.what()).find(cut.filename().string()), std::string::npos) << e.what();
            }
        }
    }
    // A file that is no recording and no folder.
    test::writeBytes(dir / "notes.bag", "#ROSBAG V1.2\n");
    const std::string message = test::errorMessageOf([&] { Dataset::open(dir / "notes.bag"); });
    EXPECT_NE(message.find("notes.bag"), std::string::npos) << message;
    fs::remove_all(dir);
}
