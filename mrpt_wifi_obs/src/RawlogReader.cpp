/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt_wifi/obs/CommandLine.h>
#include <mrpt_wifi/obs/RawlogReader.h>

#include <algorithm>
#include <chrono>
#include <stdexcept>

namespace mrpt_wifi
{
namespace
{
/** The first line of an exception's text (MRPT's carry a backtrace after it). */
/** First line of an exception's message (MRPT banner and backtrace removed). */
std::string firstLine(const std::exception& e)
{
    const std::string msg = cli::exceptionMessage(e);
    return msg.substr(0, msg.find('\n'));
}
}  // namespace

uint64_t forEachRawlogObject(
    const std::string& path,
    const std::function<void(mrpt::serialization::CSerializable::Ptr&)>& onObject,
    const std::function<void(double)>& onProgress)
{
    mrpt::io::CFileGZInputStream f;
    std::string openError;
    if (!f.open(path, openError))
        throw std::runtime_error("rawlog '" + path + "': cannot open: " + openError);
    const double total = double(std::max<uint64_t>(f.getTotalBytesCount(), 1));
    auto archive = mrpt::serialization::archiveFrom(f);
    auto lastReport = std::chrono::steady_clock::now();
    uint64_t count = 0;
    for (;;)
    {
        const uint64_t offset = f.getPosition();
        mrpt::serialization::CSerializable::Ptr obj;
        try
        {
            archive >> obj;
        }
        catch (const mrpt::serialization::CExceptionEOF&)
        {
            break;
        }
        catch (const std::exception& e)
        {
            // MRPT reports a clean end of a gzip stream as a generic "EOF" error.
            if (f.checkEOF() && std::string(e.what()).find("EOF") != std::string::npos) break;
            throw std::runtime_error(
                "rawlog '" + path + "': unreadable object #" + std::to_string(count + 1) +
                " at compressed byte offset " + std::to_string(offset) + ": " + firstLine(e));
        }
        ++count;
        onObject(obj);
        if (onProgress &&
            std::chrono::steady_clock::now() - lastReport > std::chrono::milliseconds(100))
        {
            lastReport = std::chrono::steady_clock::now();
            onProgress(std::min(1.0, double(f.getPosition()) / total));
        }
    }
    if (onProgress) onProgress(1.0);
    return count;
}

uint64_t forEachRawlogObservation(
    const std::string& path,
    const std::function<void(const mrpt::obs::CObservation::Ptr&)>& onObservation,
    const std::function<void(double)>& onProgress)
{
    return forEachRawlogObject(
        path,
        [&](mrpt::serialization::CSerializable::Ptr& obj)
        {
            if (auto sf = std::dynamic_pointer_cast<mrpt::obs::CSensoryFrame>(obj))
                for (const auto& o : *sf) onObservation(o);
            else if (auto o = std::dynamic_pointer_cast<mrpt::obs::CObservation>(obj))
                onObservation(o);
        },
        onProgress);
}

}  // namespace mrpt_wifi
