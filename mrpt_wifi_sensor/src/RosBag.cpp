/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt_wifi/sensor/RosBag.h>
#include <ros/serialization.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <topic_tools/shape_shifter.h>

#include <stdexcept>

namespace mrpt_wifi::ros1
{
void forEachBagMessage(
    const std::string& path, const std::function<void(const BagMessage&)>& onMessage,
    const std::function<void(double)>& onProgress)
{
    rosbag::Bag bag;
    try
    {
        bag.open(path, rosbag::bagmode::Read);
    }
    catch (const std::exception& e)
    {
        throw std::runtime_error("'" + path + "': not a readable ROS 1 bag (" + e.what() + ")");
    }
    try
    {
        rosbag::View view(bag);
        const double t0 = view.getBeginTime().toSec(), t1 = view.getEndTime().toSec();
        BagMessage m;
        for (const rosbag::MessageInstance& mi : view)
        {
            m.topic = mi.getTopic();
            m.datatype = mi.getDataType();
            m.md5 = mi.getMD5Sum();
            m.time = mi.getTime().toSec();
            m.bytes.resize(mi.size());
            ros::serialization::OStream out(m.bytes.data(), uint32_t(m.bytes.size()));
            mi.write(out);
            onMessage(m);
            if (onProgress && t1 > t0) onProgress((m.time - t0) / (t1 - t0));
        }
    }
    catch (const rosbag::BagException& e)
    {
        throw std::runtime_error("'" + path + "': corrupt ROS 1 bag (" + e.what() + ")");
    }
    if (onProgress) onProgress(1.0);
}

struct BagWriter::Impl
{
    rosbag::Bag bag;
};

BagWriter::BagWriter(const std::string& path) : impl_(std::make_unique<Impl>()), path_(path)
{
    try
    {
        impl_->bag.open(path, rosbag::bagmode::Write);
    }
    catch (const std::exception& e)
    {
        throw std::runtime_error("cannot create bag '" + path + "': " + e.what());
    }
}

BagWriter::~BagWriter()
{
    try
    {
        close();
    }
    catch (...)
    {
        // A destructor must not throw; close() reports failures when called explicitly.
    }
}

void BagWriter::write(
    const std::string& topic, double time, const MessageType& type, std::vector<uint8_t> bytes)
{
    // ShapeShifter carries bytes whose type is known only at run time (no generated header).
    topic_tools::ShapeShifter msg;
    msg.morph(type.md5, type.datatype, type.definition, "");
    ros::serialization::IStream in(bytes.data(), uint32_t(bytes.size()));
    msg.read(in);
    ros::Time stamp;
    stamp.fromSec(std::max(time, 1e-9));  // ROS rejects time 0 in bags
    impl_->bag.write(topic, stamp, msg);
}

void BagWriter::close()
{
    if (impl_ && impl_->bag.isOpen()) impl_->bag.close();
}

}  // namespace mrpt_wifi::ros1
