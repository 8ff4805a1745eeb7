/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt_wifi/calib/PhaseCalibrator.h>

#include <stdexcept>
#include <string>
#include <vector>

/** Splitter calibration from several captures, each feeding some of the receive chains.
 *
 * People calibrate a router through a two-way splitter: one capture feeds cores 0 and 1, the
 * next cores 0 and 3, and so on. Every capture measures its fed chains against the chain all
 * captures share (element 0 of the array: the chain every jump state is measured against);
 * the chains it does not feed still hear the transmitter over the air. The captures' results
 * are merged into one calibration of the whole array. */
namespace mrpt_wifi::calib
{
/** A set of splitter captures that cannot make one calibration; the message names the capture
 *  and the chain. */
class SplitterError : public std::runtime_error
{
public:
    using std::runtime_error::runtime_error;
};

/** How flat each element's CSI is against element 0 in one frame: the RMS [rad], across the
 *  subcarriers, of the phase of z_k = Σ_streams h_i(k)·h_0(k)^* after removing its own linear
 *  phase (the delay) and its mean. Through a splitter and equal cables both chains get the
 *  same channel, so only the chains' own ripple remains (0.006–0.009 rad on the muTrack
 *  captures). An element the splitter does not feed still hears the transmitter over the air,
 *  2–9 dB weaker and as coherent from packet to packet as a fed one, but through a multipath
 *  channel of its own: 0.016–0.34 rad. Element 0: 0. */
std::vector<double> splitterFlatness(const CalibrationFrame& f);

/** Which elements one splitter capture feeds, from its frames' flatness. */
class SplitterFeedDetector
{
public:
    /** Relative to the flattest element: fed up to this factor, not fed from `unfedRatio` on,
     *  undecided between (the muTrack captures: fed elements within 1.4× of each other,
     *  unfed ones 2.7× to 56× the fed one). */
    static constexpr double kFedRatio = 1.6, kUnfedRatio = 2.4;
    /** No element flatter than this [rad] (11°): the splitter feeds none with element 0. */
    static constexpr double kMaxFedFlatness = 0.2;

    void add(const CalibrationFrame& f);
    size_t frames() const { return frames_; }
    /** Median flatness of each element over the frames (element 0: 0). */
    std::vector<double> medianFlatness() const;

    struct Verdict
    {
        std::vector<unsigned> fed;        //!< ascending, element 0 first (when any is fed)
        std::vector<unsigned> undecided;  //!< neither clearly fed nor clearly not
        std::vector<double> flatness;     //!< medianFlatness()
    };
    Verdict decide() const;

private:
    std::vector<std::vector<float>> flatness_;  //!< [element][frame]
    size_t frames_ = 0;
};

/** The array restricted to some of its elements, in that order (same name: the same device). */
AntennaArray subArray(const AntennaArray& a, const std::vector<unsigned>& elements);

/** A frame restricted to some elements (rows, chain delays and states), in that order. */
void restrictFrame(
    const CalibrationFrame& in, const std::vector<unsigned>& elements, CalibrationFrame& out);

/** One capture's calibration of the elements it feeds. */
struct SplitterCapture
{
    std::string name;                //!< the capture (file), for messages
    std::vector<unsigned> elements;  //!< the elements it feeds, ascending, 0 first
    ChannelCalibration result;       //!< of subArray(array, elements): row r is elements[r]
};

/** What the merge did, per element ≥ 1, for the user. */
struct SplitterMergeNote
{
    unsigned element = 0;
    std::string from;                   //!< capture whose offsets the file holds
    std::vector<std::string> agreeing;  //!< other captures that fed it and agree
    double maxDisagreement_rad = 0;     //!< largest difference to those
};

/** Merges the captures of one channel into one calibration of every element of `array`
 *  (element order). An element fed by several captures takes the offsets of the one with most
 *  frames, after checking that the others agree within `maxDisagreement_rad` in a jump state
 *  they share. Throws SplitterError when an element is fed by no capture, a capture does not
 *  feed element 0 together with another one, two captures disagree on an element, or they
 *  share no jump state to compare it in. */
PhaseCalibration mergeSplitterCaptures(
    const std::vector<SplitterCapture>& captures, const AntennaArray& array,
    double maxDisagreement_rad, std::vector<SplitterMergeNote>* notes = nullptr);

/** "element 2 (core 3)" */
std::string describeElement(const AntennaArray& a, unsigned element);

}  // namespace mrpt_wifi::calib
