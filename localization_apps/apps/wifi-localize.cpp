/* mrpt_wifi — WiFi channel state information for MRPT.
 *
 * wifi-localize: live localization. Runs the sensors of a rawlog-grabber-style .ini in-process
 * (CWiFiCSISensor from the plugin given with -p, and any MRPT sensor producing
 * CObservationOdometry), turns CSI into bearings (the sensor's own `<label>_AOA` bearings when it
 * makes them, else its own BearingProcessor), and feeds them to MRPT's particle filter with the
 * WiFi bearing map as they arrive: pose estimate as TUM (flushed per line), a status line per
 * second, an optional rawlog of everything seen, and an optional live 3-D view. With
 * `map_devices = true` it also maps the transmitters it hears (wifi-iot-map's triangulation on
 * the AoA bearings along the odometry), updated while the robot drives. */
#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt/config/CConfigFile.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/gui/CDisplayWindow3D.h>
#include <mrpt/hwdrivers/CGenericSensor.h>
#include <mrpt/img/CImage.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/io/vector_loadsave.h>
#include <mrpt/opengl/CBox.h>
#include <mrpt/opengl/CFBORender.h>
#include <mrpt/opengl/CGridPlaneXY.h>
#include <mrpt/opengl/CPointCloud.h>
#include <mrpt/opengl/CSetOfLines.h>
#include <mrpt/opengl/CSetOfObjects.h>
#include <mrpt/opengl/CText.h>
#include <mrpt/opengl/CTexturedPlane.h>
#include <mrpt/opengl/stock_objects.h>
#include <mrpt/random/RandomGenerators.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/system/filesystem.h>
#include <mrpt/system/os.h>
#include <mrpt/system/string_utils.h>
#include <mrpt_wifi/localization/BearingLikelihood.h>
#include <mrpt_wifi/localization/DeviceMapper.h>
#include <mrpt_wifi/localization/LiveLocalizer.h>
#include <mrpt_wifi/localization/Trajectory2D.h>
#include <mrpt_wifi/localization/TransmitterMap.h>
#include <mrpt_wifi/obs/CObservationWiFiCSI.h>
#include <mrpt_wifi/obs/CommandLine.h>
#include <mrpt_wifi/obs/ConfigKeys.h>
#include <mrpt_wifi/obs/ConfigPaths.h>
#include <mrpt_wifi/obs/PhaseCalibration.h>
#include <mrpt_wifi/obs/bearing/BearingProcessor.h>
#include <mrpt_wifi/sensor/CWiFiCSISensor.h>
#include <mrpt_wifi/sensor/LiveBearingWorker.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <csignal>
#include <deque>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <thread>

#include "McapOutput.h"

using namespace mrpt_wifi;
using namespace mrpt_wifi::localization;
using Clock = std::chrono::steady_clock;

namespace
{
std::atomic<bool> g_stop{false};
void onSignal(int)
{
    g_stop = true;
}

double nowUnix()
{
    return mrpt::Clock::toDouble(mrpt::Clock::now());
}

/** One sensor of the .ini, run like rawlog-grabber does: its own thread calling doProcess()
 *  at its process_rate; the main thread collects with getObservations() (thread-safe). */
struct SensorRunner
{
    std::string section;
    mrpt::hwdrivers::CGenericSensor::Ptr sensor;
    std::thread thread;
    std::string error;  // set by the thread when doProcess() throws
    /** A CSI sensor's own bearing chain (`bearing_algorithm` set), or nullptr. */
    mrpt_wifi::LiveBearingWorker* bearingWorker = nullptr;
    /** Set when the runner goes before the program asked the threads to stop (an error
     *  unwinding): a joinable std::thread destroyed would terminate the program. */
    std::atomic<bool> leaving{false};

    ~SensorRunner()
    {
        leaving = true;
        if (thread.joinable()) thread.join();
    }

    void start(const std::atomic<bool>& stop)
    {
        thread = std::thread(
            [this, &stop]
            {
                const double rate = std::max(1.0, sensor->getProcessRate());
                const auto period = std::chrono::duration<double>(1.0 / rate);
                auto next = Clock::now();
                try
                {
                    while (!stop && !leaving)
                    {
                        sensor->doProcess();
                        next += std::chrono::duration_cast<Clock::duration>(period);
                        if (next < Clock::now()) next = Clock::now();
                        std::this_thread::sleep_until(next);
                    }
                }
                catch (const std::exception& e)
                {
                    error = cli::exceptionMessage(e);
                }
            });
    }
};

/** The bearing chain wifi-localize runs itself on CSI of sensors that make no bearings: keys
 *  `bearing_*` of the [wifi-localize] section (same meaning as csi-bearings' options). */
std::unique_ptr<bearing::BearingProcessor> makeFallbackProcessor(
    const mrpt::config::CConfigFileBase& ini, const std::string& iniDir, bool keepProfile)
{
    const std::string s = "wifi-localize";
    const std::string algo = ini.read_string(s, "bearing_algorithm", "");
    if (algo.empty()) return nullptr;
    // From the .ini's folder; arrays also by name from the data folder (ConfigPaths.h).
    const auto resolveAs = [&](const std::string& p, const std::string& key, const char* kind)
    {
        const auto r = config::resolveConfigPath(p, iniDir, kind, "[" + s + "] " + key);
        if (!r.note.empty()) std::cerr << "wifi-localize: note: " << r.note << "\n";
        return r.path;
    };
    const auto path = [&](const std::string& key, const char* kind)
    { return resolveAs(ini.read_string(s, key, ""), key, kind); };
    const std::string array = path("bearing_array", "arrays");
    if (array.empty())
        throw std::invalid_argument(
            "[wifi-localize] bearing_algorithm is set: bearing_array (the receive array YAML) is "
            "needed too");
    auto est = bearing::createEstimator(algo);
    if (est->syntheticAperture())
        throw std::invalid_argument(
            "[wifi-localize] bearing_algorithm = " + algo +
            ": a synthetic aperture needs the peers' recordings of this robot; bearings from it "
            "come from csi-bearings or wifi-sar (their rawlog then goes to wifi-pf-localization)");
    est->options().keepProfile = keepProfile;
    CalibrationStore calib;
    if (const auto c = path("bearing_calibration", ""); !c.empty())
        calib = CalibrationStore::open(c);
    bearing::BearingProcessor::Options wo;
    wo.stride = unsigned(std::max(1, ini.read_int(s, "bearing_stride", 1)));
    auto p = std::make_unique<bearing::BearingProcessor>(
        CsiPreprocessor(PreprocessOptions(), AntennaArray::fromYamlFile(array), calib),
        std::move(est), wo);
    // As the sensor's key of the same name: FILE (every transmitter) and/or MAC=FILE,
    // comma-separated; read under its former name bearing_tx_array too.
    std::vector<std::string> txArrays;
    mrpt::system::tokenize(
        config::readString(ini, s, config::sectionKeys(s), "bearing_tx_arrays", ""), ", \t",
        txArrays);
    for (const auto& t : txArrays)
        if (const auto eq = t.find('='); eq == std::string::npos)
            p->setDefaultTransmitterArray(
                AntennaArray::fromYamlFile(resolveAs(t, "bearing_tx_arrays", "arrays")));
        else
            p->setTransmitterArray(
                MacAddress::fromString(t.substr(0, eq)),
                AntennaArray::fromYamlFile(
                    resolveAs(t.substr(eq + 1), "bearing_tx_arrays", "arrays")));
    return p;
}

/** Writes observations to a rawlog from its own thread, so compression never delays the
 *  filter; close() writes everything queued. */
class RawlogWriter
{
public:
    explicit RawlogWriter(const std::string& path)
    {
        if (!out_.open(path, 1)) throw std::runtime_error("cannot write '" + path + "'");
        thread_ = std::thread(
            [this]
            {
                auto arch = mrpt::serialization::archiveFrom(out_);
                std::unique_lock<std::mutex> lk(mtx_);
                for (;;)
                {
                    cv_.wait(lk, [this] { return closing_ || !queue_.empty(); });
                    if (queue_.empty()) return;  // closing, all written
                    auto o = std::move(queue_.front());
                    queue_.pop_front();
                    lk.unlock();
                    arch << *o;
                    ++written_;
                    lk.lock();
                }
            });
    }
    ~RawlogWriter() { close(); }
    void push(mrpt::obs::CObservation::Ptr o)
    {
        {
            std::lock_guard<std::mutex> lk(mtx_);
            queue_.push_back(std::move(o));
        }
        cv_.notify_one();
    }
    void close()
    {
        {
            std::lock_guard<std::mutex> lk(mtx_);
            closing_ = true;
        }
        cv_.notify_one();
        if (thread_.joinable()) thread_.join();
        out_.close();
    }
    uint64_t written() const { return written_; }

private:
    mrpt::io::CFileGZOutputStream out_;
    std::thread thread_;
    std::mutex mtx_;
    std::condition_variable cv_;
    std::deque<mrpt::obs::CObservation::Ptr> queue_;
    bool closing_ = false;
    std::atomic<uint64_t> written_{0};
};

/** The live window: AP map, particles, estimate, bearing rays of the last second, the latest
 *  bearing–delay profile (when the fallback chain keeps one). */
class LiveView
{
public:
    LiveView(
        const CWiFiBearingMap& map, const mrpt::math::TPose2D& roomMin,
        const mrpt::math::TPose2D& roomMax)
        : win_("wifi-localize", 1000, 700)
    {
        auto& scene = win_.get3DSceneAndLock();
        auto grid = mrpt::opengl::CGridPlaneXY::Create(
            float(roomMin.x), float(roomMax.x), float(roomMin.y), float(roomMax.y), 0, 1);
        grid->setColor(0.75, 0.75, 0.75);
        scene->insert(grid);
        auto aps = mrpt::opengl::CSetOfObjects::Create();
        map.getVisualizationInto(*aps);
        scene->insert(aps);
        particles_ = mrpt::opengl::CPointCloud::Create();
        particles_->setColor(0.2, 0.4, 1.0);
        particles_->setPointSize(4.0);
        scene->insert(particles_);
        rays_ = mrpt::opengl::CSetOfLines::Create();
        rays_->setColor(0.9, 0.5, 0.0, 0.6);
        rays_->setLineWidth(1.5);
        scene->insert(rays_);
        estimate_ = mrpt::opengl::stock_objects::CornerXYZSimple(0.8f, 5.0f);
        scene->insert(estimate_);
        devices_ = mrpt::opengl::CSetOfObjects::Create();
        scene->insert(devices_);
        // The latest bearing-delay profile, as a picture beside the room (x: angle -90..90 deg,
        // y: delay), with a frame around it.
        const double px0 = roomMax.x + 0.5, pw = 0.8 * (roomMax.y - roomMin.y);
        profile_ = mrpt::opengl::CTexturedPlane::Create(
            float(px0), float(px0 + pw), float(roomMin.y), float(roomMax.y));
        scene->insert(profile_);
        auto frame = mrpt::opengl::CSetOfLines::Create();
        frame->appendLine(px0, roomMin.y, 0, px0 + pw, roomMin.y, 0);
        frame->appendLineStrip(px0 + pw, roomMax.y, 0);
        frame->appendLineStrip(px0, roomMax.y, 0);
        frame->appendLineStrip(px0, roomMin.y, 0);
        frame->setColor(0.2, 0.2, 0.2);
        scene->insert(frame);
        profileLabel_ = mrpt::opengl::CText::Create("bearing profile (none yet)");
        profileLabel_->setLocation(px0, roomMax.y + 0.2, 0);
        scene->insert(profileLabel_);
        roomMax_ = roomMax.x + 0.5 + pw;
        win_.unlockAccess3DScene();
        camTarget_ = mrpt::math::TPoint2Df(
            float(0.5 * (roomMin.x + roomMax_)), float(0.5 * (roomMin.y + roomMax.y)));
        camZoom_ = float(1.7 * std::max(roomMax_ - roomMin.x, roomMax.y - roomMin.y));
        win_.setCameraPointingToPoint(camTarget_.x, camTarget_.y, 0);
        win_.setCameraZoom(camZoom_);
        win_.setCameraElevationDeg(kElevation_deg);
        win_.setCameraAzimuthDeg(-90);
    }

    ~LiveView() { stopThread(); }

    bool isOpen() { return win_.isOpen(); }

    /** What the window should show next; built by the filter's thread (cheap copies), drawn by
     *  the view's own thread, so rendering never delays the filter. */
    struct Snapshot
    {
        std::vector<float> px, py;
        mrpt::math::TPose2D mean;
        std::vector<std::array<double, 4>> rays;   // x0 y0 x1 y1
        std::optional<mrpt::img::CImage> profile;  // x: angle, y: delay or power
        std::string profileLabel;
        std::string status;
        std::vector<DeviceEstimate> devices;  // live device map (localized ones drawn)
    };

    static Snapshot snapshot(
        const LiveLocalizer& loc, const std::deque<CObservationWiFiBearing::Ptr>& recent,
        const bearing::BearingProfile* profile, const std::string& status,
        const std::vector<DeviceEstimate>* devices = nullptr)
    {
        Snapshot s;
        const auto& pdf = loc.particles();
        s.px.reserve(pdf.size()), s.py.reserve(pdf.size());
        for (const auto& p : pdf.m_particles)
            s.px.push_back(float(p.d.x)), s.py.push_back(float(p.d.y));
        s.mean = loc.estimate();
        const double len = 6.0;
        for (const auto& b : recent)
        {
            const auto* tx = loc.wifiMap().transmitters().find(b->transmitter);
            if (b->hasAod && tx && loc.wifiMap().likelihoodOptions.use.aod)
            {
                const double a = tx->pose.phi + b->aod_rad;
                s.rays.push_back(
                    {tx->pose.x, tx->pose.y, tx->pose.x + len * std::cos(a),
                     tx->pose.y + len * std::sin(a)});
            }
            if (loc.wifiMap().likelihoodOptions.use.aoa)
            {
                const auto sp = mrpt::poses::CPose2D(s.mean) + mrpt::poses::CPose2D(b->sensorPose);
                const double a = sp.phi() + b->aoa_rad;
                s.rays.push_back(
                    {sp.x(), sp.y(), sp.x() + len * std::cos(a), sp.y() + len * std::sin(a)});
            }
        }
        if (profile && profile->values.size() > 0)
        {
            const Eigen::MatrixXf& v = profile->values;  // [angle][delay]
            s.profileLabel = profile->label + (v.cols() == 1 ? " over angle" : ": angle x delay");
            const float mx = std::max(v.maxCoeff(), 1e-20f);
            if (v.cols() == 1)  // 1-D: a curve over angle, drawn into a picture
            {
                const int w = 360, h = 240;
                mrpt::img::CImage img(w, h, mrpt::img::CH_RGB);
                img.filledRectangle(0, 0, w - 1, h - 1, mrpt::img::TColor(255, 255, 255));
                const double n = double(v.rows() - 1);
                for (int i = 0; i + 1 < v.rows(); ++i)
                    img.line(
                        int(w * i / n), int((h - 1) * v(i, 0) / mx), int(w * (i + 1) / n),
                        int((h - 1) * v(i + 1, 0) / mx), mrpt::img::TColor(200, 30, 30), 2);
                s.profile = std::move(img);
            }
            else
            {
                // x: angle, y: delay (upwards), colour: power (dark blue .. yellow)
                mrpt::img::CImage img(int(v.rows()), int(v.cols()), mrpt::img::CH_RGB);
                for (int a = 0; a < v.rows(); ++a)
                    for (int d = 0; d < v.cols(); ++d)
                    {
                        const float q = std::clamp(v(a, d) / mx, 0.0f, 1.0f);
                        const auto r = uint8_t(255 * q), g = uint8_t(255 * std::sqrt(q)),
                                   b = uint8_t(120 * (1 - q));
                        img.setPixel(
                            a, int(v.cols()) - 1 - d, (size_t(r) << 16) | (size_t(g) << 8) | b);
                    }
                s.profile = std::move(img);
            }
        }
        s.status = status;
        if (devices) s.devices = *devices;
        return s;
    }

    /** Hands a snapshot to the view thread (replacing one not drawn yet). */
    void post(Snapshot s)
    {
        {
            std::lock_guard<std::mutex> lk(mtx_);
            next_ = std::move(s);
        }
        if (!thread_.joinable())
            thread_ = std::thread(
                [this]
                {
                    while (!stop_)
                    {
                        std::optional<Snapshot> latest;
                        {
                            std::lock_guard<std::mutex> lk(mtx_);
                            latest.swap(next_);
                        }
                        if (latest) draw(*latest);
                        std::this_thread::sleep_for(std::chrono::milliseconds(100));
                    }
                });
    }

    void stopThread()
    {
        stop_ = true;
        if (thread_.joinable()) thread_.join();
    }

    /** Draws a snapshot now (on the caller's thread; stopThread() first). */
    void draw(const Snapshot& s)
    {
        win_.get3DSceneAndLock();
        particles_->clear();
        for (size_t i = 0; i < s.px.size(); ++i) particles_->insertPoint(s.px[i], s.py[i], 0.3f);
        estimate_->setPose(mrpt::poses::CPose3D(s.mean.x, s.mean.y, 0.05, s.mean.phi, 0, 0));
        rays_->clear();
        for (const auto& r : s.rays) rays_->appendLine(r[0], r[1], 0.1, r[2], r[3], 0.1);
        devices_->clear();
        for (const auto& d : s.devices)
        {
            if (!d.localized) continue;
            // The estimate (red square) and its 95% ellipse (k = sqrt(chi2_2(0.95)) = 2.4477).
            auto e = mrpt::opengl::CSetOfLines::Create();
            e->setColor(0.85, 0.1, 0.1);
            e->setLineWidth(2);
            const double a = 0.5 * (d.cov[0] + d.cov[2]),
                         b = std::sqrt(
                             0.25 * (d.cov[0] - d.cov[2]) * (d.cov[0] - d.cov[2]) +
                             d.cov[1] * d.cov[1]);
            const double l1 = std::sqrt(std::max(0.0, a + b)), l2 = std::sqrt(std::max(0.0, a - b));
            const double th = 0.5 * std::atan2(2 * d.cov[1], d.cov[0] - d.cov[2]);
            const auto pt = [&](int i)
            {
                const double u = 2 * M_PI * i / 36, px = 2.4477 * l1 * std::cos(u),
                             py = 2.4477 * l2 * std::sin(u);
                return std::array<double, 2>{
                    d.x + std::cos(th) * px - std::sin(th) * py,
                    d.y + std::sin(th) * px + std::cos(th) * py};
            };
            auto p0 = pt(0);
            e->appendLine(p0[0], p0[1], 0.15, p0[0], p0[1], 0.15);
            for (int i = 1; i <= 36; ++i)
            {
                const auto q = pt(i);
                e->appendLineStrip(q[0], q[1], 0.15);
            }
            devices_->insert(e);
            auto box = mrpt::opengl::CBox::Create(
                mrpt::math::TPoint3D(d.x - 0.1, d.y - 0.1, 0.1),
                mrpt::math::TPoint3D(d.x + 0.1, d.y + 0.1, 0.3));
            box->setColor(0.85, 0.1, 0.1);
            devices_->insert(box);
            auto t = mrpt::opengl::CText::Create(d.name.empty() ? d.mac.asString() : d.name);
            t->setLocation(d.x + 0.2, d.y + 0.2, 0.3);
            t->setColor(0.6, 0, 0);
            devices_->insert(t);
        }
        if (s.profile)
        {
            profile_->assignImage(*s.profile);
            profileLabel_->setString(s.profileLabel);
        }
        win_.unlockAccess3DScene();
        win_.addTextMessage(5, 5, s.status, 0);
        win_.addTextMessage(5, 25, kLegend, 1);
        win_.forceRepaint();
    }

    /** Saves what the window shows (same scene, camera and status text) as a PNG, rendered
     *  off-screen (MRPT's CFBORender, EGL): reading a window's frame back is unreliable on
     *  virtual displays such as Xvfb. */
    void screenshot(const std::string& file, const std::string& status)
    {
        mrpt::opengl::COpenGLScene copy;
        {
            auto& scene = win_.get3DSceneAndLock();
            copy = *scene;
            win_.unlockAccess3DScene();
        }
        auto vp = copy.getViewport("main");
        mrpt::opengl::CCamera cam;
        cam.setPointingAt(camTarget_.x, camTarget_.y, 0);
        cam.setZoomDistance(camZoom_);
        cam.setElevationDegrees(kElevation_deg);
        cam.setAzimuthDegrees(-90);
        vp->setCustomBackgroundColor(mrpt::img::TColorf(0.6f, 0.6f, 0.6f));
        vp->addTextMessage(5, 5, status, 0);
        vp->addTextMessage(5, 25, kLegend, 1);
        mrpt::opengl::CFBORender render(mrpt::opengl::CFBORender::Parameters(1000, 700));
        render.setCamera(copy, cam);
        mrpt::img::CImage img;
        render.render_RGB(copy, img);
        if (!img.saveToFile(file)) throw std::runtime_error("cannot write '" + file + "'");
    }

private:
    static constexpr float kElevation_deg = 80;
    static constexpr const char* kLegend =
        "blue: particles, axes: estimate, orange: bearings of the last second, red: mapped "
        "devices (95%), right: the latest profile";
    mrpt::gui::CDisplayWindow3D win_;
    mrpt::math::TPoint2Df camTarget_;
    float camZoom_ = 10;
    double roomMax_ = 0;  // right end of the drawing (room + profile)
    mrpt::opengl::CPointCloud::Ptr particles_;
    mrpt::opengl::CSetOfLines::Ptr rays_;
    mrpt::opengl::CSetOfObjects::Ptr estimate_, devices_;
    mrpt::opengl::CTexturedPlane::Ptr profile_;
    mrpt::opengl::CText::Ptr profileLabel_;
    std::thread thread_;
    std::mutex mtx_;
    std::optional<Snapshot> next_;
    std::atomic<bool> stop_{false};
};

std::string fmt(double v, int prec = 2)
{
    char b[64];
    std::snprintf(b, sizeof(b), "%.*f", prec, v);
    return b;
}

/** "std_x_m,std_y_m,corr_xy,std_phi_deg" of a pose covariance. */
std::string covarianceCsvCells(const mrpt::math::CMatrixDouble33& c)
{
    const double sx = std::sqrt(std::max(c(0, 0), 0.0)), sy = std::sqrt(std::max(c(1, 1), 0.0));
    return fmt(sx, 5) + "," + fmt(sy, 5) + "," +
           fmt(sx > 0 && sy > 0 ? c(0, 1) / (sx * sy) : 0.0, 4) + "," +
           fmt(mrpt::RAD2DEG(std::sqrt(std::max(c(2, 2), 0.0))), 3);
}

/** The live device map in one line: `devices: name (x, y) +-sigma [m], ...`. */
std::string devicesLine(const std::vector<DeviceEstimate>& devs)
{
    std::string s = "devices:";
    for (const auto& d : devs)
    {
        s += " " + (d.name.empty() ? d.mac.asString() : d.name);
        if (d.localized)
            s += " (" + fmt(d.x) + ", " + fmt(d.y) + ") +-" +
                 fmt(std::sqrt(std::max(0.0, std::max(d.cov[0], d.cov[2])))) + "m";
        else
            s += " (not yet: " + std::to_string(d.rays) + " bearings)";
        s += ",";
    }
    if (devs.empty())
        s += " none yet";
    else
        s.pop_back();
    return s;
}
}  // namespace

int main(int argc, char** argv)
{
    return cli::runMain(
        "wifi-localize",
        [&]
        {
            TCLAP::CmdLine cmd(
                "Live WiFi localization: runs the sensors of a rawlog-grabber-style .ini "
                "in-process (CWiFiCSISensor via -p <build or prefix>/lib/libmrpt_wifi_sensor.so, "
                "odometry sensors) and "
                "MRPT's particle filter with the WiFi bearing map on their observations as they "
                "arrive. The same .ini holds the pf-localization sections and [wifi-localize] "
                "(see share/localization/wifi-localize-rt-ac86u.ini for a real router, "
                "share/localization/wifi-localize-emulator.ini for rt-ac86u-emulator). Exit "
                "status: 0 the run "
                "ended (duration, Ctrl+C/SIGTERM, idle, window closed) with usable bearings; 1 "
                "bad command line or .ini, or a sensor failed; when no usable CSI arrived for "
                "no_csi_timeout_s (or in the whole run), the cause: 4 router control failed "
                "(ssh), 5 no datagrams on the UDP port, 6 datagrams but no CSI frame passed "
                "(router_address, MAC/RSSI filters, format), 7 CSI frames but no bearings "
                "(bearing chain, calibration, array), 8 bearings but none the AP map weighs "
                "(channel, map, AoD without the APs' calibration). See docs/troubleshooting.md.",
                ' ', "0.1");
            TCLAP::UnlabeledValueArg<std::string> argIni(
                "config", "sensors + localization .ini", true, "", "CONFIG.ini", cmd);
            TCLAP::MultiArg<std::string> argPlugin(
                "p", "plugin",
                "Plugin module(s) to load first, as rawlog-grabber -p: "
                "<build or prefix>/lib/libmrpt_wifi_sensor.so for CWiFiCSISensor",
                false, "LIB.so", cmd);
            TCLAP::ValueArg<std::string> argOut(
                "o", "out-dir", "Output folder (estimate_tum.txt, estimate_cov.csv, summary.txt)",
                false, "wifi-localize-out", "DIR", cmd);
            TCLAP::ValueArg<std::string> argRawlog(
                "r", "rawlog", "Also record every observation seen to this rawlog", false, "",
                "OUT.rawlog", cmd);
            TCLAP::ValueArg<double> argDuration(
                "d", "duration", "Stop after this many seconds (0: until Ctrl+C)", false, 0, "S",
                cmd);
            TCLAP::ValueArg<double> argIdle(
                "", "stop-when-idle",
                "Stop when no observation arrived for this long, after the first one (replays)",
                false, 0, "S", cmd);
            TCLAP::ValueArg<std::string> argGt(
                "g", "ground-truth-tum",
                "True trajectory on the sensors' clock: errors in the summary", false, "", "GT.txt",
                cmd);
            TCLAP::ValueArg<double> argThr(
                "", "converged-threshold", "Error [m] below which the filter counts as converged",
                false, 1.0, "M", cmd);
            TCLAP::ValueArg<double> argHold(
                "", "converged-hold", "... and must stay for this long [s]", false, 5.0, "S", cmd);
            TCLAP::ValueArg<std::string> argDevTruth(
                "", "devices-truth",
                "With map_devices: true device positions (transmitters YAML): errors in the "
                "summary",
                false, "", "TX.yaml", cmd);
            TCLAP::ValueArg<unsigned> argSeed(
                "", "seed",
                "Seed of the particle filter's random numbers, as wifi-pf-localization --seed: "
                "two runs then differ only in how the clock batched the observations",
                false, 1, "N", cmd);
            TCLAP::SwitchArg argView("", "view", "Live 3-D window", cmd);
            TCLAP::ValueArg<std::string> argShot(
                "", "screenshot", "With --view: save the window to this PNG at the end", false, "",
                "FILE.png", cmd);
            TCLAP::SwitchArg argQuiet("q", "quiet", "No status lines", cmd);
            TCLAP::ValueArg<std::string> argMcap(
                "", "mcap", mcap_output::optionHelp(), false, "", "OUT.mcap", cmd);
            TCLAP::SwitchArg argKeepWaiting(
                "", "keep-waiting",
                "When no usable CSI arrives for [wifi-localize] no_csi_timeout_s (default 20 s; 0 "
                "waits forever), warn with the cause and keep waiting instead of exiting with "
                "the cause's status",
                cmd);
            if (const int rc = cli::parseCommandLine(cmd, argc, const_cast<const char**>(argv));
                rc >= 0)
                return rc;

            // ---- plugins, configuration, filter
            for (const auto& p : argPlugin.getValue())
            {
                cli::loadPlugin(p);
            }
            const std::string iniPath = argIni.getValue();
            if (!mrpt::system::fileExists(iniPath))
                throw std::runtime_error("cannot read '" + iniPath + "'");
            mrpt::config::CConfigFile ini(iniPath);
            // A misspelt section name would leave its keys unread without a word.
            for (const auto& w : config::unreadSections(ini, config::pfLocalizationMrptSections()))
                std::cerr << "wifi-localize: warning: " << iniPath << ": " << w << "\n";
            // Relative paths in the .ini: from its own folder (ConfigPaths.h).
            const std::string iniDir = config::iniDirectoryOf(iniPath);
            // Before the filter draws its first particles (MRPT seeds from the clock).
            mrpt::random::getRandomGenerator().randomize(argSeed.getValue());
            LiveLocalizer loc(ini, iniDir);
            if (loc.areaFromInitialPdf())
                std::cerr
                    << "note: the map sets no area (min_x ... max_y in its creationOpts): the "
                       "robot is kept inside the init_PDF box\n";
            if (!loc.areaWarning().empty())
                std::cerr << "wifi-localize: warning: " << iniPath << ": " << loc.areaWarning()
                          << "\n";
            auto fallback = makeFallbackProcessor(ini, iniDir, false);
            const double noCsiTimeout_s = ini.read_double("wifi-localize", "no_csi_timeout_s", 20);
            if (!(noCsiTimeout_s >= 0))
                throw std::invalid_argument(
                    iniPath + ": [wifi-localize] no_csi_timeout_s = " +
                    ini.read_string("wifi-localize", "no_csi_timeout_s", "") +
                    ": seconds without usable CSI before giving up, >= 0 (0: wait forever)");
            LiveDeviceMapper mapper(ini, "wifi-localize");
            TransmitterMap devTruth;
            if (argDevTruth.isSet())
                devTruth = TransmitterMap::fromYamlFile(argDevTruth.getValue());
            const auto nameDevices = [&]
            {
                auto devs = mapper.devices();
                for (auto& d : devs)
                    if (const auto* t = devTruth.find(d.mac))
                        d.name = t->name;
                    else if (const auto* k = loc.wifiMap().transmitters().find(d.mac))
                        d.name = k->name;
                return devs;
            };
            std::vector<DeviceEstimate> liveDevices;  // the latest live map, named
            auto lastProfileWanted = Clock::now();
            std::optional<bearing::BearingProfile> latestProfile;  // for the view

            const std::string outDir = argOut.getValue();
            mrpt::system::createDirectory(outDir);
            if (!mrpt::system::directoryExists(outDir))
                throw std::runtime_error("cannot create " + outDir);
            std::ofstream tum(outDir + "/estimate_tum.txt");
            tum << "# wifi-localize estimate (PF mean refined by the window smoother, with "
                   "odometry or without): t x y z qx qy qz qw\n"
                << std::flush;
            // The filter's own mean as well, as wifi-pf-localization keeps it.
            std::ofstream pfTum(outDir + "/pf_estimate_tum.txt");
            pfTum << "# wifi-localize particle filter mean: t x y z qx qy qz qw\n" << std::flush;
            // The same poses with their uncertainty (LiveLocalizer::uncertainty(): reported, then
            // the particles' alone), so a user can check that it covers the error and weigh the
            // estimate when fusing it.
            std::ofstream covCsv(outDir + "/estimate_cov.csv");
            covCsv << "t,x_m,y_m,phi_deg,std_x_m,std_y_m,corr_xy,std_phi_deg,particles_std_x_m,"
                      "particles_std_y_m,particles_corr_xy,particles_std_phi_deg\n"
                   << std::flush;
            std::unique_ptr<RawlogWriter> rawlog;
            if (argRawlog.isSet()) rawlog = std::make_unique<RawlogWriter>(argRawlog.getValue());
            // --mcap: each pose output with its covariance as it is made (closed at the end).
            std::unique_ptr<ros2::LocalizationMcap> mcapOut;
            if (argMcap.isSet())
                mcapOut = std::make_unique<ros2::LocalizationMcap>(argMcap.getValue(), true);
            double mcapRaysUntil = -std::numeric_limits<double>::infinity();

            // ---- sensors: every section with a `driver`, as rawlog-grabber does
            // Declared before the sensors: their threads read it until they are joined, also
            // when an error unwinds this scope.
            std::atomic<bool> stopSensors{false};
            std::vector<std::unique_ptr<SensorRunner>> sensors;
            std::vector<std::string> sections;
            ini.getAllSections(sections);
            for (const auto& sec : sections)
            {
                const std::string driver = ini.read_string(sec, "driver", "");
                if (driver.empty()) continue;
                auto r = std::make_unique<SensorRunner>();
                r->section = sec;
                r->sensor = mrpt::hwdrivers::CGenericSensor::createSensorPtr(driver);
                if (!r->sensor)
                    throw std::runtime_error(
                        "[" + sec + "] driver = " + driver +
                        ": no such sensor class (forgot -p <build or "
                        "prefix>/lib/libmrpt_wifi_sensor.so?)");
                r->sensor->loadConfig(ini, sec);
                sensors.push_back(std::move(r));
            }
            // Every section checked before any sensor starts (opens sockets, replays, ...).
            for (auto& r : sensors)
            {
                r->sensor->initialize();
                if (auto* csiSensor = dynamic_cast<CWiFiCSISensor*>(r->sensor.get()))
                    r->bearingWorker = csiSensor->bearingWorker();
            }
            if (sensors.empty())
                throw std::runtime_error(
                    iniPath + ": no sensor section (a section with `driver = ...`)");

            std::signal(SIGINT, onSignal);
            std::signal(SIGTERM, onSignal);
            for (auto& s : sensors) s->start(stopSensors);

            std::unique_ptr<LiveView> view;
            if (argView.getValue())
            {
                const auto rd = [&](const char* k)
                { return ini.read_double("LocalizationExperiment", k, 0); };
                view = std::make_unique<LiveView>(
                    loc.wifiMap(),
                    mrpt::math::TPose2D(rd("init_PDF_min_x"), rd("init_PDF_min_y"), 0),
                    mrpt::math::TPose2D(rd("init_PDF_max_x"), rd("init_PDF_max_y"), 0));
            }

            // ---- the loop
            // CSI labels whose sensor makes its own `<label>_AOA` bearings (`bearing_algorithm`
            // set in its section, see share/rawlog-grabber/csi_live_bearings.ini): wifi-localize
            // uses those and never estimates again on that CSI, from the first frame on (the
            // frame arrives before its bearing). Sensors found to send bearings are added too.
            std::set<std::string> sensorBearingLabels;
            for (const auto& s : sensors)
                if (!ini.read_string(s->section, "bearing_algorithm", "").empty())
                    sensorBearingLabels.insert(s->sensor->getSensorLabel());
            std::deque<CObservationWiFiBearing::Ptr> recent;  // last second, for the view
            // Nothing is kept per pose for the whole run (a live run may last days): the lags
            // as a histogram, the estimates outside the map's area as a count. Only scoring
            // against a ground truth (-g) keeps every estimate, for the end.
            LagRecord lags;  // per pose output [s]
            double lastLag_s = NAN, lastPoseTime = NAN;
            uint64_t outsideArea = 0;
            const bool keepEstimates = argGt.isSet();
            Trajectory2D est;
            std::vector<std::array<double, 3>> estCov;  // position covariance per pose [m²]
            uint64_t nCsi = 0, nOdo = 0, nBearings = 0, nOther = 0, nFallback = 0;
            uint64_t secBearings = 0, secPoses = 0, poseOutputs = 0;
            double newestObs = 0, lastObsWall = 0, firstObsWall = 0, firstObsTime = 0;
            const auto t0 = Clock::now();
            auto lastStatus = t0, lastView = t0, lastMapUpdate = t0;
            const auto elapsed = [&]
            { return std::chrono::duration<double>(Clock::now() - t0).count(); };
            // Filter steps with the bearings queued (one per max_bearings_per_step), then one
            // pose output; also called between observations of a long batch, so a busy
            // bearing chain can't hold the estimate back.
            auto lastOutput = Clock::now();
            long long lastOutputStamp_us = std::numeric_limits<long long>::min();
            const auto filterAndOutput = [&]() -> bool
            {
                bool stepped = false;
                const auto stepStart = Clock::now();
                while (loc.pendingBearings() > 0 &&
                       Clock::now() - stepStart < std::chrono::milliseconds(50))
                    stepped = loc.step(nowUnix()) || stepped;
                lastOutput = Clock::now();
                if (!stepped) return false;
                const auto m = loc.estimate();
                const double t = loc.lastStepTime();
                // A bearing that arrived late (older than the last output) refines the filter
                // but gives no newer pose: the trajectory stays strictly increasing in time, as
                // TUM readers expect.
                if (std::llround(t * 1e6) <= lastOutputStamp_us) return true;
                lastOutputStamp_us = std::llround(t * 1e6);
                lastLag_s = nowUnix() - t;
                lags.add(lastLag_s);
                lastPoseTime = t;
                if (loc.wifiMap().area() && !loc.wifiMap().inArea(m.x, m.y)) ++outsideArea;
                ++poseOutputs;
                ++secPoses;
                if (keepEstimates) est.push_back(t, m);
                const auto u = loc.uncertainty();
                // Flushed per line: a reader follows the estimate as it is made.
                tum << Trajectory2D::tumLine(t, m) << std::flush;
                pfTum << Trajectory2D::tumLine(t, u.particlesMean) << std::flush;
                const auto& c = u.reported;
                if (keepEstimates) estCov.push_back({c(0, 0), c(0, 1), c(1, 1)});
                covCsv << fmt(t, 6) << "," << fmt(m.x, 4) << "," << fmt(m.y, 4) << ","
                       << fmt(mrpt::RAD2DEG(m.phi), 3) << "," << covarianceCsvCells(c) << ","
                       << covarianceCsvCells(u.particles) << std::endl;
                if (mcapOut)
                {
                    const auto& txMap = loc.wifiMap().transmitters();
                    if (poseOutputs == 1) mcapOut->transmitters(t, mcap_output::landmarksOf(txMap));
                    std::array<double, 9> c9;
                    for (int i = 0; i < 9; ++i) c9[size_t(i)] = c(i / 3, i % 3);
                    mcapOut->pose(t, m.x, m.y, m.phi, &c9);
                    // The bearings since the previous pose, from this one.
                    mcap_output::Rays rays;
                    for (const auto& b : recent)
                        if (const double bt = mrpt::Clock::toDouble(b->timestamp);
                            bt > mcapRaysUntil && bt <= t)
                            rays.push_back(
                                mcap_output::rayOf(recordFromObservation(*b), m, &txMap));
                    mcapRaysUntil = t;
                    if (!rays.empty()) mcapOut->bearingRays(t, rays);
                }
                return true;
            };
            std::string stopReason = "Ctrl+C";
            std::string lastStatusText = "(no data yet)";

            // ---- no usable CSI: after no_csi_timeout_s without a bearing from a transmitter
            // of the map (or, with map_devices, one the device map takes), say why (the first
            // stage of the chain that got nothing) and exit with that cause's status, unless
            // --keep-waiting.
            uint64_t nMapped = 0;     // bearings the filter weighs or the device map uses
            uint64_t nUnweighed = 0;  // from the map's transmitters, without an angle it weighs
            std::set<std::string> unmappedHeard, channelsSeen;
            // CSI frames per transmitter, for the summary (bounded: a busy street has many).
            constexpr size_t kMaxSendersCounted = 64;
            std::map<MacAddress, uint64_t> csiPerSender;
            std::map<std::string, uint64_t> fallbackRejects;  // why our chain gave no bearing
            const auto& weighs = loc.wifiMap().likelihoodOptions;
            const auto noteMapped = [&](const CObservationWiFiBearing& b)
            {
                const auto record = recordFromObservation(b);
                const bool fromMap = loc.wifiMap().transmitters().find(b.transmitter) != nullptr;
                if ((fromMap && recordWeighed(record, weighs.model, weighs.use)) ||
                    (mapper.enabled() && record.hasAoa))
                    ++nMapped;
                else if (fromMap)
                    ++nUnweighed;
                else if (unmappedHeard.size() < 6)
                    unmappedHeard.insert(b.transmitter.asString());
            };
            struct Window
            {
                Clock::time_point start;
                uint64_t csi = 0, bearings = 0, mapped = 0, unweighed = 0;
                std::vector<CWiFiCSISensor::Counters> counters;  // per sensor (CSI ones)
            };
            const auto csiSensorOf = [](const SensorRunner& r)
            { return dynamic_cast<CWiFiCSISensor*>(r.sensor.get()); };
            const auto openWindow = [&]
            {
                Window w;
                w.start = Clock::now();
                w.csi = nCsi, w.bearings = nBearings, w.mapped = nMapped, w.unweighed = nUnweighed;
                for (const auto& r : sensors)
                    w.counters.push_back(
                        csiSensorOf(*r) ? csiSensorOf(*r)->counters() : CWiFiCSISensor::Counters());
                return w;
            };
            // {exit status, cause and what to check}; status 0: nothing to report (usable
            // bearings came, or every source is a replay that ended).
            const auto diagnose = [&](const Window& w) -> std::pair<int, std::string>
            {
                const double secs = std::chrono::duration<double>(Clock::now() - w.start).count();
                const std::string during = "in " + fmt(secs, 0) + " s";
                if (nMapped > w.mapped) return {0, ""};
                int status = 0;
                std::string text;
                bool csiSensors = false, framesCame = false, replaysEnded = true;
                for (size_t i = 0; i < sensors.size(); ++i)
                {
                    const auto* c = csiSensorOf(*sensors[i]);
                    if (!c) continue;
                    csiSensors = true;
                    const auto d = c->diagnoseNoFrames(w.counters[i], secs);
                    using Cause = CWiFiCSISensor::NoFrameDiagnosis::Cause;
                    if (d.cause != Cause::ReplayEnded) replaysEnded = false;
                    if (d.cause == Cause::None)
                    {
                        framesCame = true;
                        continue;
                    }
                    const int st = d.cause == Cause::ControlFailed ? cli::kExitRouterControlFailed
                                   : d.cause == Cause::NoMatchingFrames ? cli::kExitNoMatchingFrames
                                   : d.cause == Cause::NoDatagrams      ? cli::kExitNoDatagrams
                                                                        : 0;
                    // The most specific cause names the status: control failure, then
                    // datagrams that matched nothing, then silence.
                    const auto rank = [](int x)
                    {
                        return x == cli::kExitRouterControlFailed ? 3
                               : x == cli::kExitNoMatchingFrames  ? 2
                               : x == cli::kExitNoDatagrams       ? 1
                                                                  : 0;
                    };
                    if (rank(st) > rank(status)) status = st;
                    if (st) text += (text.empty() ? "" : "; ") + d.text;
                }
                if (nCsi == w.csi && nBearings == w.bearings)
                {
                    if (csiSensors && replaysEnded) return {0, ""};
                    if (csiSensors && !framesCame && status) return {status, text};
                    return {
                        cli::kExitNoDatagrams,
                        "no CSI observation from the sensors " + during + " (" +
                            (csiSensors ? "frames were delivered but none reached the filter"
                                        : "no CWiFiCSISensor section: which sensor makes "
                                          "the CSI?") +
                            ")"};
                }
                std::string channels;
                for (const auto& c : channelsSeen) channels += (channels.empty() ? "" : ", ") + c;
                if (nBearings == w.bearings)
                {
                    std::string why;
                    bool sensorChains = false;
                    for (const auto& r : sensors)
                        if (r->bearingWorker)
                        {
                            sensorChains = true;
                            const auto st = r->bearingWorker->stats();
                            why +=
                                " [" + r->section + "]'s chain: " + std::to_string(st.estimated) +
                                " estimated, " + std::to_string(st.rejected) + " rejected, " +
                                std::to_string(st.calibrationErrors) + " calibration mismatches;";
                        }
                    if (!fallback && !sensorChains)
                        return {
                            cli::kExitNoBearings,
                            std::to_string(nCsi - w.csi) + " CSI frames " + during +
                                " but nothing turns them into bearings: set "
                                "bearing_algorithm and bearing_array (and "
                                "bearing_calibration) in [wifi-localize] or in the CSI "
                                "sensor's section"};
                    for (const auto& [reason, n] : fallbackRejects)
                        why += " " + reason + " " + std::to_string(n) + ";";
                    return {
                        cli::kExitNoBearings,
                        std::to_string(nCsi - w.csi) + " CSI frames " + during + " (channels " +
                            channels + ") but no bearing from them:" + why +
                            " check that bearing_calibration was made on this channel and "
                            "bandwidth and that bearing_array has this receiver's antennas "
                            "in its port order (array mismatch: more receive chains than "
                            "array elements), with 'cores: [...]' when the router reports "
                            "only some cores (core_mask)"};
                }
                if (nUnweighed > w.unweighed)
                    return {
                        cli::kExitNoMappedBearings,
                        std::to_string(nUnweighed - w.unweighed) +
                            " bearings from the map's access points " + during +
                            ", none with an angle the map weighs (" +
                            weighedAnglesString(weighs.model, weighs.use) +
                            "): AoD needs the access points' transmit-chain calibration "
                            "(wifi-calibrate --transmit-chains, in bearing_calibration) and "
                            "bearing_tx_arrays; AoA needs use_aoa = true in the map's "
                            "likelihoodOpts; a σ above max_std_deg is not weighed"};
                std::string heard;
                for (const auto& m : unmappedHeard) heard += (heard.empty() ? "" : ", ") + m;
                return {
                    cli::kExitNoMappedBearings,
                    std::to_string(nBearings - w.bearings) + " bearings " + during +
                        ", none from a transmitter of the AP map (heard " + heard + " on " +
                        channels +
                        "): wrong channel (the map's access points transmit on another one: "
                        "the sensor's channel / chanspec) or the map lacks them (its "
                        "transmitters_file, MAC addresses as csi-router scan lists them)"};
            };
            const Window wholeRun = openWindow();
            Window window = wholeRun;
            auto lastWindowMove = Clock::now();
            int exitStatus = 0;
            std::string noCsiCause;  // the last diagnosis printed
            while (!g_stop)
            {
                if (nMapped > window.mapped &&
                    Clock::now() - lastWindowMove > std::chrono::milliseconds(100))
                {
                    window = openWindow();
                    lastWindowMove = Clock::now();
                }
                if (noCsiTimeout_s > 0 &&
                    Clock::now() - window.start >= std::chrono::duration<double>(noCsiTimeout_s))
                {
                    const auto [status, text] = diagnose(window);
                    window = openWindow();
                    if (status != 0)
                    {
                        noCsiCause = text;
                        if (argKeepWaiting.getValue())
                            std::cerr << "wifi-localize: warning: no usable CSI for "
                                      << fmt(noCsiTimeout_s, 0) << " s: " << text
                                      << " (--keep-waiting: still waiting)\n";
                        else
                        {
                            std::cerr << "wifi-localize: error: no usable CSI for "
                                      << fmt(noCsiTimeout_s, 0) << " s: " << text
                                      << " (exit status " << status
                                      << "; --keep-waiting or [wifi-localize] "
                                         "no_csi_timeout_s = 0 waits instead)\n";
                            exitStatus = status;
                            stopReason = "no usable CSI for " + fmt(noCsiTimeout_s, 0) + " s";
                            break;
                        }
                    }
                }
                if (argDuration.getValue() > 0 && elapsed() >= argDuration.getValue())
                {
                    stopReason = "duration reached";
                    break;
                }
                if (argIdle.getValue() > 0 && lastObsWall > 0 &&
                    elapsed() - lastObsWall > argIdle.getValue())
                {
                    stopReason = "no observation for " + fmt(argIdle.getValue(), 1) + " s";
                    break;
                }
                if (view && !view->isOpen())
                {
                    stopReason = "window closed";
                    break;
                }
                bool failed = false;
                for (auto& s : sensors)
                    if (!s->error.empty())
                    {
                        std::cerr << "wifi-localize: sensor [" << s->section << "]: " << s->error
                                  << "\n";
                        failed = true;
                    }
                if (failed) throw std::runtime_error("a sensor failed (see above)");

                // Everything the sensors have, in time order.
                std::multimap<mrpt::Clock::time_point, mrpt::serialization::CSerializable::Ptr> all;
                for (auto& s : sensors)
                {
                    mrpt::hwdrivers::CGenericSensor::TListObservations l;
                    s->sensor->getObservations(l);
                    all.insert(l.begin(), l.end());
                }
                for (auto& [t, o] : all)
                {
                    auto obs = std::dynamic_pointer_cast<mrpt::obs::CObservation>(o);
                    if (!obs) continue;
                    if (rawlog) rawlog->push(obs);
                    lastObsWall = elapsed();
                    if (firstObsWall == 0) firstObsWall = lastObsWall;
                    newestObs = std::max(newestObs, mrpt::Clock::toDouble(obs->timestamp));
                    if (firstObsTime == 0) firstObsTime = mrpt::Clock::toDouble(obs->timestamp);
                    if (auto odo = std::dynamic_pointer_cast<mrpt::obs::CObservationOdometry>(obs))
                    {
                        ++nOdo;
                        loc.addOdometry(*odo);
                        if (mapper.enabled()) mapper.addOdometry(*odo);
                        // Our bearing chain, as csi-bearings', combines only the frames taken
                        // near the newest; without odometry only those of the last 0.15 s.
                        if (fallback)
                            fallback->addOdometry(odo->timestamp, odo->odometry.asTPose());
                        // So does a CSI sensor's own chain (rawlog-grabber has no way to give
                        // it the odometry of another sensor; here we do).
                        for (auto& sr : sensors)
                            if (sr->bearingWorker)
                                sr->bearingWorker->addOdometry(
                                    odo->timestamp, odo->odometry.asTPose());
                    }
                    else if (auto b = std::dynamic_pointer_cast<CObservationWiFiBearing>(obs))
                    {
                        // The sensor's own live bearings: from now on they replace ours.
                        const auto& l = b->sensorLabel;
                        if (l.size() > 4 && l.compare(l.size() - 4, 4, "_AOA") == 0)
                            sensorBearingLabels.insert(l.substr(0, l.size() - 4));
                        ++nBearings, ++secBearings;
                        noteMapped(*b);
                        loc.addBearing(b);
                        if (mapper.enabled()) mapper.addBearing(*b);
                        recent.push_back(b);
                    }
                    else if (auto csi = std::dynamic_pointer_cast<CObservationWiFiCSI>(obs))
                    {
                        ++nCsi;
                        if (channelsSeen.size() < 4) channelsSeen.insert(csi->chanspec.asString());
                        if (csiPerSender.size() < kMaxSendersCounted ||
                            csiPerSender.count(csi->transmitter))
                            ++csiPerSender[csi->transmitter];
                        // The view shows a bearing-delay profile twice a second: only then
                        // does the estimator keep one (it costs more than the bearing).
                        bool keep = false;
                        if (fallback && view)
                            fallback->estimator().options().keepProfile = keep =
                                Clock::now() - lastProfileWanted > std::chrono::milliseconds(500);
                        RejectReason rejectReason = RejectReason::Accepted;
                        if (fallback && !sensorBearingLabels.count(csi->sensorLabel))
                        {
                            if (auto fb = fallback->process(*csi, &rejectReason))
                            {
                                if (keep && fallback->estimator().lastProfile())
                                {
                                    latestProfile = *fallback->estimator().lastProfile();
                                    lastProfileWanted = Clock::now();
                                }
                                ++nFallback, ++nBearings, ++secBearings;
                                noteMapped(*fb);
                                loc.addBearing(fb);
                                if (mapper.enabled())
                                {
                                    mapper.addBearing(*fb);
                                    // The rawlog then holds what wifi-iot-map needs.
                                    if (rawlog) rawlog->push(fb);
                                }
                                recent.push_back(fb);
                            }
                            else if (rejectReason != RejectReason::Accepted)
                                ++fallbackRejects[toString(rejectReason)];
                        }
                    }
                    else
                        ++nOther;
                    if (Clock::now() - lastOutput > std::chrono::milliseconds(50))
                        filterAndOutput();
                }
                while (!recent.empty() &&
                       mrpt::Clock::toDouble(recent.front()->timestamp) < newestObs - 1.0)
                    recent.pop_front();

                if (!filterAndOutput()) std::this_thread::sleep_for(std::chrono::milliseconds(2));

                const auto now = Clock::now();
                const double sinceStatus = std::chrono::duration<double>(now - lastStatus).count();
                std::string statusText;
                if (sinceStatus >= 1.0 || (view && now - lastView > std::chrono::milliseconds(200)))
                {
                    const auto m = loc.estimate();
                    statusText =
                        "t=" + fmt(elapsed(), 1) + "s pose=(" + fmt(m.x) + ", " + fmt(m.y) + ", " +
                        fmt(mrpt::RAD2DEG(m.phi), 0) + " deg) spread=" + fmt(loc.spread_m()) +
                        "m bearings/s=" +
                        fmt(double(secBearings) / std::max(sinceStatus, 1e-3), 0) +
                        " poses/s=" + fmt(double(secPoses) / std::max(sinceStatus, 1e-3), 1) +
                        " lag=" +
                        (lags.count() == 0 ? std::string("-") : fmt(lastLag_s * 1e3, 0) + "ms") +
                        (loc.hasOdometry() ? "" : " (no odometry)");
                }
                if (mapper.enabled() &&
                    std::chrono::duration<double>(now - lastMapUpdate).count() >=
                        mapper.updatePeriod_s())
                {
                    mapper.update();
                    liveDevices = nameDevices();
                    lastMapUpdate = Clock::now();
                    if (!argQuiet.getValue())
                        std::cerr << "[wifi-localize] t=" << fmt(elapsed(), 1) << "s "
                                  << devicesLine(liveDevices) << "\n";
                }
                if (!statusText.empty() && mapper.enabled())
                    statusText += " devices=" + std::to_string(std::count_if(
                                                    liveDevices.begin(), liveDevices.end(),
                                                    [](const auto& d) { return d.localized; }));
                if (!statusText.empty()) lastStatusText = statusText;
                if (sinceStatus >= 1.0)
                {
                    if (!argQuiet.getValue()) std::cerr << "[wifi-localize] " << statusText << "\n";
                    secBearings = secPoses = 0;
                    lastStatus = now;
                }
                if (view && now - lastView > std::chrono::milliseconds(200))
                {
                    view->post(LiveView::snapshot(
                        loc, recent, latestProfile ? &*latestProfile : nullptr, statusText,
                        &liveDevices));
                    lastView = now;
                }
            }
            stopSensors = true;
            for (auto& s : sensors)
                if (s->thread.joinable()) s->thread.join();
            if (mapper.enabled())  // the final map: everything seen
            {
                mapper.update();
                liveDevices = nameDevices();
            }
            if (mcapOut)
            {
                if (mapper.enabled() && poseOutputs > 0)
                    mcapOut->devices(lastPoseTime, mcap_output::devicesOf(liveDevices));
                mcapOut->close();
            }
            if (view && !argShot.getValue().empty())
            {
                view->stopThread();
                view->draw(LiveView::snapshot(
                    loc, recent, latestProfile ? &*latestProfile : nullptr, lastStatusText,
                    &liveDevices));
                view->screenshot(argShot.getValue(), lastStatusText);
            }

            if (rawlog) rawlog->close();

            // ---- summary
            const double runTime = elapsed();
            const double active = std::max(1e-9, lastObsWall - firstObsWall);
            std::ostringstream sum;
            sum << "wifi-localize summary\n"
                << "  stopped        : " << stopReason << " after " << fmt(runTime, 1) << " s\n"
                << "  observations   : " << nCsi << " CSI, " << nOdo << " odometry, " << nBearings
                << " bearings (" << nFallback << " computed by wifi-localize, "
                << (sensorBearingLabels.empty()
                        ? std::string("none")
                        : std::to_string(sensorBearingLabels.size()) + " sensor(s)")
                << " with own bearings), " << nOther << " other\n"
                << "  first obs. at  : " << fmt(firstObsTime, 6) << " (UNIX time, sensor clock)\n";
            if (!csiPerSender.empty())
            {
                sum << "  CSI per sender :";
                for (const auto& [mac, n] : csiPerSender) sum << " " << mac.asString() << " " << n;
                if (csiPerSender.size() == kMaxSendersCounted)
                    sum << " (the first " << kMaxSendersCounted << " senders heard)";
                sum << "\n";
            }
            // What a chain's windows combined, given the odometry or not (as in csi-bearings).
            const auto windows = [](bool odometry)
            {
                return odometry ? "a window holds only the frames taken near the newest"
                                : "a window holds only the frames of its last "
                                  "window.max_span_without_odometry_s (0.15 s unless set)";
            };
            if (nFallback > 0)
                sum << "  bearing chain  : "
                    << (fallback->hasOdometry() ? "odometry given: " : "no odometry: ")
                    << windows(fallback->hasOdometry()) << "\n";
            for (const auto& sr : sensors)
                if (sr->bearingWorker)
                {
                    const auto given = sr->bearingWorker->stats().odometry;
                    sum << "  sensor chain   : [" << sr->section << "] "
                        << (given > 0 ? std::to_string(given) + " odometry readings given: "
                                      : std::string("no odometry: "))
                        << windows(given > 0) << "\n";
                }
            sum << "  bearings used  : " << loc.bearingsUsed()
                << " (unknown transmitter: " << loc.unknownTransmitter()
                << "; with an angle the map weighs: " << loc.bearingsWeighed() << ")\n"
                << "  filter steps   : " << loc.steps() << " ("
                << (loc.options().maxBearingsPerStep == 0
                        ? std::string("all queued bearings per step")
                        : "up to " + std::to_string(loc.options().maxBearingsPerStep) +
                              " bearings per step, more when queued over " +
                              fmt(loc.options().maxQueue_s, 2) + " s")
                << ")\n"
                << "  pose outputs   : " << poseOutputs << " ("
                << fmt(double(poseOutputs) / active, 1) << " /s while data flowed)\n"
                << "  lag [ms]       : p50 " << fmt(lags.percentile(0.5) * 1e3, 1) << ", p99 "
                << fmt(lags.percentile(0.99) * 1e3, 1) << ", max "
                << fmt(lags.percentile(1.0) * 1e3, 1)
                << " (pose output time - timestamp of the newest bearing in it)\n"
                << "  odometry       : "
                << (loc.hasOdometry()
                        ? "yes"
                        : "none (unknown motion model: " + loc.unknownMotion().asString() + ")")
                << "\n"
                << "  recovery       : " << loc.recoveryOptions().asString() << ": "
                << recoverySummary(loc.recovery()) << "\n"
                << "  window smoother: " << loc.smoother().options().asString();
            if (loc.smoother().options().enabled)
                sum << ": " << loc.smoother().accepted() << " of " << loc.smoother().solves()
                    << " solves used (" << loc.smoother().restarts()
                    << " restarts: newest bearings unexplained)"
                    << (loc.hasOdometry() || loc.smoother().options().withoutOdometry
                            ? ""
                            : " (without_odometry = false: it needs odometry)")
                    << ", " << fmt(loc.smoother().solveTime_s(), 2) << " s";
            sum << "\n";
            if (const auto area = areaSummary(loc.wifiMap(), outsideArea); !area.empty())
                sum << "  area           : " << area << "\n";
            if (argGt.isSet() && !est.empty())
            {
                const auto gt = Trajectory2D::fromTumFile(argGt.getValue());
                std::vector<double> times, errs;
                std::vector<bool> inside95;  // error inside the filter's own 95 % ellipse
                for (size_t i = 0; i < est.size(); ++i)
                {
                    mrpt::math::TPose2D g;
                    if (!gt.interpolate(est.t[i], g, 0.5)) continue;
                    times.push_back(est.t[i] - est.t.front());
                    const double ex = est.poses[i].x - g.x, ey = est.poses[i].y - g.y;
                    errs.push_back(std::hypot(ex, ey));
                    const auto& c = estCov[i];
                    inside95.push_back(mahalanobis2(c[0], c[1], c[2], ex, ey) <= kChi2TwoDof95);
                }
                if (errs.empty())
                    throw std::runtime_error("the ground truth doesn't overlap the estimate");
                double tc = -1;  // first time after which the error stays low for `hold` s
                for (size_t i = 0; i < errs.size() && tc < 0; ++i)
                {
                    size_t j = i;
                    while (j < errs.size() && errs[j] < argThr.getValue() &&
                           times[j] - times[i] < argHold.getValue())
                        ++j;
                    if (j < errs.size() && errs[j] < argThr.getValue()) tc = times[i];
                }
                std::vector<double> after;
                size_t afterInside = 0;
                for (size_t i = 0; i < errs.size(); ++i)
                    if (tc >= 0 && times[i] >= tc)
                        after.push_back(errs[i]), afterInside += inside95[i] ? 1 : 0;
                sum << "  error (all)    : " << computeStats(errs).asString() << "\n";
                if (tc >= 0)
                    sum << "  converged after: " << fmt(tc) << " s\n"
                        << "  after converged: " << computeStats(after).asString() << "\n"
                        << "  in 95 % ellipse: "
                        << fmt(100.0 * double(afterInside) / double(after.size()), 1)
                        << " % of the estimates after convergence (estimate_cov.csv's σ)\n";
                else
                    sum << "  converged after: never\n";
            }
            if (mapper.enabled())
            {
                saveDeviceCsv(outDir + "/devices.csv", liveDevices);
                saveDeviceYaml(outDir + "/devices.yaml", liveDevices);
                sum << "  device map     : " << mapper.bearings() << " AoA bearings, "
                    << liveDevices.size() << " devices (" << mapper.warnings().summary()
                    << "), written to " << outDir << "/devices.csv\n";
                std::vector<double> errs;
                for (const auto& d : liveDevices)
                {
                    const double sx = std::sqrt(std::max(0.0, d.cov[0])),
                                 sy = std::sqrt(std::max(0.0, d.cov[2]));
                    sum << "    " << d.mac.asString() << " " << d.name << " "
                        << (d.localized ? "OK " : "-- ") << "x=" << fmt(d.x) << " y=" << fmt(d.y)
                        << " sigma=(" << fmt(sx) << ", " << fmt(sy) << ") m bearings=" << d.rays
                        << " inliers=" << d.inliers;
                    if (const auto* t = devTruth.find(d.mac); t && d.localized)
                    {
                        errs.push_back(std::hypot(d.x - t->pose.x, d.y - t->pose.y));
                        sum << " error=" << fmt(errs.back()) << " m";
                    }
                    if (!d.note.empty()) sum << " (" << d.note << ")";
                    sum << "\n";
                }
                if (argDevTruth.isSet())
                    sum << "  device error   : " << computeStats(errs).asString() << "\n";
            }
            // E.g. AoA-only bearings on a map set to AoD only: the run ends normally, its
            // estimate the prior's mean throughout.
            if (loc.bearingsUsed() > 0 && loc.bearingsWeighed() == 0)
            {
                const auto& lo = loc.wifiMap().likelihoodOptions;
                const std::string w = "none of the " + std::to_string(loc.bearingsUsed()) +
                                      " bearings has an angle the map weighs (" +
                                      weighedAnglesString(lo.model, lo.use) +
                                      "): the filter weighed nothing, its estimate is the "
                                      "initial distribution moved by the motion model";
                sum << "  WARNING        : " << w << "\n";
                std::cerr << "wifi-localize: warning: " << w << "\n";
            }
            // A run that never had a usable bearing failed, however it ended: its status names
            // the cause (as after no_csi_timeout_s).
            if (nMapped == 0 && exitStatus == 0)
                if (const auto [status, text] = diagnose(wholeRun); status != 0)
                {
                    exitStatus = status;
                    noCsiCause = text;
                    std::cerr << "wifi-localize: error: no usable CSI in the whole run: " << text
                              << " (exit status " << status << ")\n";
                }
            if (nCsi == 0)
                sum << "  WARNING        : 0 CSI frames received"
                    << (noCsiCause.empty() ? std::string() : ": " + noCsiCause) << "\n";
            else if (exitStatus != 0)
                sum << "  WARNING        : no usable CSI: " << noCsiCause << "\n";
            if (exitStatus != 0) sum << "  exit status    : " << exitStatus << "\n";
            std::cout << sum.str();
            std::ofstream(outDir + "/summary.txt") << sum.str();
            return exitStatus;
        });
}
