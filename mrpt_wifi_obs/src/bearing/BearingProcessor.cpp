/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt_wifi/obs/bearing/BearingProcessor.h>

#include <algorithm>
#include <cmath>

namespace mrpt_wifi::bearing
{
BearingProcessor::BearingProcessor(
    CsiPreprocessor preprocessor, std::unique_ptr<BearingEstimator> estimator, Options options)
    : pre_(std::move(preprocessor)),
      est_(std::move(estimator)),
      opts_(options),
      windows_(
          std::max(options.windowCapacity, est_ ? est_->framesWanted() : 1), options.windowMaxAge_s)
{
}

void BearingProcessor::setTransmitterArray(const MacAddress& mac, AntennaArray array)
{
    txArrays_[mac] = std::move(array);
}

void BearingProcessor::setDefaultTransmitterArray(AntennaArray array)
{
    defaultTxArray_ = std::move(array);
}

const AntennaArray* BearingProcessor::txArrayOf(const MacAddress& mac) const
{
    const auto it = txArrays_.find(mac);
    if (it != txArrays_.end()) return &it->second;
    return defaultTxArray_ ? &*defaultTxArray_ : nullptr;
}

CObservationWiFiBearing::Ptr BearingProcessor::process(
    const CObservationWiFiCSI& csi, RejectReason* reason)
{
    lastFrame_ = nullptr;
    lastResult_ = BearingResult();
    CsiWindow& window = windows_.of(csi.transmitter);
    CleanCsi& slot = window.slot();
    const RejectReason r = pre_.process(csi, slot);
    if (reason) *reason = r;
    if (r != RejectReason::Accepted) return nullptr;
    window.commit();
    lastFrame_ = &window.newest();

    unsigned& since = sinceLast_[csi.transmitter];
    if (++since < opts_.stride) return nullptr;
    since = 0;

    window.recent(est_->framesWanted(), frames_);
    EstimatorContext ctx;
    ctx.rxArray = &pre_.rxArray();
    ctx.txArrayOf = [this](const MacAddress& m) { return txArrayOf(m); };
    if (!est_->estimate(frames_, ctx, lastResult_) || !lastResult_.valid) return nullptr;

    auto b = CObservationWiFiBearing::Create();
    const BearingResult& res = lastResult_;
    b->timestamp = csi.timestamp;
    b->sensorLabel = csi.sensorLabel + "_AOA";
    b->sensorPose = csi.sensorPose;
    b->transmitter = csi.transmitter;
    b->chanspec = csi.chanspec;
    b->rssi_dBm = csi.rssi_dBm;
    b->algorithm = est_->name();
    b->framesUsed = uint16_t(std::min<unsigned>(res.framesUsed, 65535));
    b->pathsDetected = uint8_t(std::min<unsigned>(res.pathsDetected, 255));
    b->aoa_rad = res.aoa_rad;
    b->aoaStd_rad = res.aoaStd_rad;
    b->aoaAmbiguous = res.aoaAmbiguous;
    b->aoaMirror_rad = res.aoaMirror_rad;
    const PhaseCalibration* txCal = lastFrame_->txCalibration;
    b->hasAod = res.hasAod && (txCal || opts_.uncalibratedAod);
    b->aod_rad = res.aod_rad;
    // The calibration's own error (what it left on its drive) adds to the estimator's.
    b->aodStd_rad = txCal ? std::hypot(res.aodStd_rad, txCal->aodResidual_rad) : res.aodStd_rad;
    b->aodAmbiguous = res.aodAmbiguous;
    b->aodMirror_rad = res.aodMirror_rad;
    b->hasDelay = res.hasDelay;
    b->delay_s = res.delay_s;
    b->quality = res.quality;
    return b;
}

}  // namespace mrpt_wifi::bearing
