/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt_wifi/obs/CObservationWiFiCSI.h>

#include <cstdint>
#include <deque>
#include <functional>
#include <string>

namespace mrpt_wifi::emulator
{
/** The emulator's end of an emulated serial port: a pseudo-terminal (openpty) in raw mode,
 * whose slave (/dev/pts/N, or a symbolic link to it) a program opens as it would open
 * /dev/ttyUSB0. Lines are queued and written without blocking; the queue is bounded (a reader
 * that never comes costs memory up to kMaxQueuedBytes, then lines are dropped and counted).
 * The emulator keeps the slave open itself, so what is written before the reader opens the
 * port waits in the terminal's buffer as it would in a USB-serial adapter's. */
class PtySerialPort
{
public:
    static constexpr size_t kMaxQueuedBytes = 1 << 20;

    /** Opens the pseudo-terminal; `linkPath` (empty: none) becomes a symbolic link to its
     * slave, replacing a stale link but never a file. Throws std::runtime_error. */
    explicit PtySerialPort(const std::string& linkPath);
    ~PtySerialPort();
    PtySerialPort(const PtySerialPort&) = delete;
    PtySerialPort& operator=(const PtySerialPort&) = delete;

    const std::string& slavePath() const { return slavePath_; }
    /** The path a reader should open: the link if there is one, else the slave. */
    std::string devicePath() const { return linkPath_.empty() ? slavePath_ : linkPath_; }
    int masterFd() const { return master_; }

    /** Queues a line (its '\n' included); false if the queue is full (counted as dropped). */
    bool submit(std::string line);
    /** Writes what the terminal takes now; each line completely written goes to `onWritten`. */
    void flush(const std::function<void(const std::string&)>& onWritten);
    bool pending() const { return !queue_.empty(); }
    /** Bytes written but not read yet by the reader of the slave (lost if the port closes). */
    size_t unreadBytes() const;

    uint64_t linesWritten() const { return linesWritten_; }
    uint64_t linesDropped() const { return linesDropped_; }
    uint64_t bytesWritten() const { return bytesWritten_; }

private:
    int master_ = -1, slave_ = -1;
    std::string slavePath_, linkPath_;
    std::deque<std::string> queue_;
    size_t queuedBytes_ = 0, offset_ = 0;  //!< bytes of queue_.front() already written
    uint64_t linesWritten_ = 0, linesDropped_ = 0, bytesWritten_ = 0;
};

/** An esp-csi `CSI_DATA` line (the 24-field get-started layout, '\n'-terminated) carrying the
 * L-LTF of pair (0, 0) of a 20 MHz frame: 64 subcarriers in FFT order, imag then real, as
 * int8 scaled so the largest component is `peak` (what the ESP32's AGC does, roughly).
 * Throws std::invalid_argument for a frame that isn't 20 MHz. */
std::string esp32CsiLine(
    const CObservationWiFiCSI& obs, uint32_t seq, uint64_t localTimestamp_us, int peak = 60);

}  // namespace mrpt_wifi::emulator
