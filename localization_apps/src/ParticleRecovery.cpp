/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/core/bits_math.h>
#include <mrpt/math/wrap2pi.h>
#include <mrpt/poses/CPosePDFParticles.h>
#include <mrpt/random/RandomGenerators.h>
#include <mrpt_wifi/localization/IniValues.h>
#include <mrpt_wifi/localization/ParticleRecovery.h>
#include <mrpt_wifi/localization/UnknownMotion.h>
#include <mrpt_wifi/obs/ConfigKeys.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace mrpt_wifi::localization
{
void ParticleRecoveryOptions::loadFromConfigFile(
    const mrpt::config::CConfigFileBase& c, const std::string& s)
{
    config::requireKnownKeys(c, s, config::sectionKeys("ParticleRecovery"));
    requireIniNumbers(c, s, {"rate_hz", "window_s", "min_agreement", "max_std_deg"});
    rate_hz = c.read_double(s, "rate_hz", rate_hz);
    window_s = c.read_double(s, "window_s", window_s);
    minAgreement = c.read_double(s, "min_agreement", minAgreement);
    maxStd_deg = c.read_double(s, "max_std_deg", maxStd_deg);
    if (!(rate_hz >= 0) || !std::isfinite(rate_hz))
        throw std::invalid_argument("[" + s + "] rate_hz must be >= 0");
    if (!(window_s > 0) || !std::isfinite(window_s))
        throw std::invalid_argument("[" + s + "] window_s must be > 0");
    if (!(maxStd_deg > 0)) throw std::invalid_argument("[" + s + "] max_std_deg must be > 0");
    if (!(minAgreement >= 0 && minAgreement <= 1))
        throw std::invalid_argument("[" + s + "] min_agreement must be in [0, 1]");
}

std::string ParticleRecoveryOptions::asString() const
{
    if (!(rate_hz > 0)) return "off";
    std::ostringstream o;
    o << "re-seeding at " << rate_hz << "/s while under " << 100 * minAgreement << " % of the last "
      << window_s << " s of bearings (sigma <= " << maxStd_deg << " deg) agree with the estimate";
    return o.str();
}

ParticleRecovery::ParticleRecovery(const ParticleRecoveryOptions& o, const CWiFiBearingMap* map)
    : o_(o), map_(map)
{
}

void ParticleRecovery::reset()
{
    estimate_.reset();
    checks_.clear();
    recovering_ = false;
}

void ParticleRecovery::checkBearing(double t_s, const CObservationWiFiBearing& b)
{
    if (!map_ || !estimate_ || !(o_.rate_hz > 0)) return;
    // Only sharp bearings tell a lost filter: judge each angle the map uses by its own σ.
    const double maxStd = mrpt::DEG2RAD(o_.maxStd_deg);
    const auto& use = map_->likelihoodOptions.use;
    const bool sharp =
        (use.aoa && b.aoaStd_rad <= maxStd) || (use.aod && b.hasAod && b.aodStd_rad <= maxStd);
    if (!sharp) return;
    const auto& e = *estimate_;
    // An estimate outside the area disagrees with every bearing.
    const auto agrees = map_->inArea(e.x, e.y) ? map_->agrees(b, e) : std::optional<bool>(false);
    if (agrees) checks_.emplace_back(t_s, *agrees);
}

double ParticleRecovery::agreement() const
{
    if (checks_.empty()) return std::nan("");
    const auto n =
        std::count_if(checks_.begin(), checks_.end(), [](const auto& c) { return c.second; });
    return double(n) / double(checks_.size());
}

double ParticleRecovery::reseedRadius_m() const
{
    if (!map_ || !map_->area()) return 0;
    const auto& a = *map_->area();
    return std::hypot(a.max.x - a.min.x, a.max.y - a.min.y);
}

double ParticleRecovery::reseedFraction(double t_s, double dt_s)
{
    while (!checks_.empty() && checks_.front().first < t_s - o_.window_s) checks_.pop_front();
    // Enough bearings to judge by: a few disagree by chance, most of a window only when the
    // estimate is off.
    const size_t kMinChecks = 8;
    const bool was = recovering_;
    recovering_ = map_ && map_->area() && o_.rate_hz > 0 && checks_.size() >= kMinChecks &&
                  agreement() < o_.minAgreement;
    if (!recovering_) return 0;
    ++steps_;
    if (!was) ++episodes_;
    return std::min(0.5, 1.0 - std::exp(-o_.rate_hz * std::max(dt_s, 0.0)));
}

mrpt::obs::CActionRobotMovement2D withReseeding(
    const mrpt::obs::CActionRobotMovement2D& action, double reseedFraction, double radius_m)
{
    mrpt::obs::CActionRobotMovement2D a = action;
    const size_t nSamples = 1000;
    const size_t nJumps = size_t(std::lround(std::clamp(reseedFraction, 0.0, 1.0) * nSamples));
    if (nJumps == 0 || !action.poseChange) return a;
    auto pdf = mrpt::poses::CPosePDFParticles::Create(nSamples);
    auto& rng = mrpt::random::getRandomGenerator();
    for (size_t i = 0; i < nSamples; ++i)
    {
        auto& d = pdf->m_particles[i].d;
        pdf->m_particles[i].log_w = -std::log(double(nSamples));  // drawn by linear weight
        if (i < nJumps)
        {
            const double r = radius_m * std::sqrt(rng.drawUniform(0.0, 1.0));
            const double dir = rng.drawUniform(-M_PI, M_PI);
            d.x = r * std::cos(dir), d.y = r * std::sin(dir);
            d.phi = rng.drawUniform(-M_PI, M_PI);
        }
        else
        {
            mrpt::poses::CPose2D s;
            action.poseChange->drawSingleSample(s);
            d = s.asTPose();
        }
    }
    a.poseChange = pdf;
    keepUsableByMrptFilter(a);
    return a;
}

std::string recoverySummary(const ParticleRecovery& r)
{
    return std::to_string(r.recoveryEpisodes()) + " episodes, " +
           std::to_string(r.recoverySteps()) + " steps re-seeding particles";
}

std::string areaSummary(
    const CWiFiBearingMap& map, const std::vector<mrpt::math::TPose2D>& estimates)
{
    return areaSummary(
        map, uint64_t(std::count_if(
                 estimates.begin(), estimates.end(),
                 [&](const auto& p) { return !map.inArea(p.x, p.y); })));
}

std::string areaSummary(const CWiFiBearingMap& map, uint64_t outside)
{
    const auto& a = map.area();
    if (!a) return {};
    std::ostringstream o;
    o << std::fixed << std::setprecision(2) << "x " << a->min.x << ".." << a->max.x << " y "
      << a->min.y << ".." << a->max.y << " m, " << outside << " estimates outside it";
    return o.str();
}

}  // namespace mrpt_wifi::localization
