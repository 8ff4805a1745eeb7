#!/usr/bin/python3
"""A ROS 2 Humble-style SQLite bag (rosbag2's sqlite3 storage) written with Python's own sqlite3,
for the rosbag2 tests of csi-import. The messages come CDR-encoded from ros2_bag_writer.mjs
(npm's @foxglove/rosmsg2-serialization); this script only stores them as rosbag2 does: tables
schema, metadata, topics and messages, and metadata.yaml beside the .db3.

  ros2_sqlite_bag.py MESSAGES.json BAG_DIR [iron|iron-float32-wifi]
      writes BAG_DIR/bag_0.db3 and BAG_DIR/metadata.yaml; "iron" adds the message_definitions
      table Iron and later keep, "iron-float32-wifi" with an older rf_msgs/msg/Wifi (float32
      CSI) in it.
"""
import base64
import json
import os
import sqlite3
import sys


def main():
    source, bag_dir = sys.argv[1], sys.argv[2]
    variant = sys.argv[3] if len(sys.argv) > 3 else "humble"
    with open(source, encoding="utf-8") as f:
        content = json.load(f)
    os.makedirs(bag_dir, exist_ok=True)
    db_path = os.path.join(bag_dir, "bag_0.db3")
    if os.path.exists(db_path):
        os.remove(db_path)
    db = sqlite3.connect(db_path)
    db.executescript(
        """
        CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL);
        CREATE TABLE metadata(id INTEGER PRIMARY KEY, metadata_version INTEGER NOT NULL,
                              metadata TEXT NOT NULL);
        CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL,
                            serialization_format TEXT NOT NULL,
                            offered_qos_profiles TEXT NOT NULL);
        CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL,
                              timestamp INTEGER NOT NULL, data BLOB NOT NULL);
        CREATE INDEX timestamp_idx ON messages (timestamp ASC);
        """
    )
    if variant in ("iron", "iron-float32-wifi"):
        db.execute(
            "CREATE TABLE message_definitions(id INTEGER PRIMARY KEY, topic_type TEXT NOT NULL, "
            "encoding TEXT NOT NULL, encoded_message_definition TEXT NOT NULL, "
            "type_description_hash TEXT NOT NULL)"
        )
        for type_name, text in content["definitions"].items():
            if variant == "iron-float32-wifi" and type_name == "rf_msgs/msg/Wifi":
                text = content["float32_wifi"]
            db.execute(
                "INSERT INTO message_definitions (topic_type, encoding, "
                "encoded_message_definition, type_description_hash) VALUES (?, 'ros2msg', ?, '')",
                (type_name, text),
            )
    iron = variant.startswith("iron")
    db.execute("INSERT INTO schema VALUES (?, ?)", (4 if iron else 3, "iron" if iron else "humble"))
    for t in content["topics"]:
        db.execute(
            "INSERT INTO topics VALUES (?, ?, ?, ?, ?)",
            (t["id"], t["name"], t["type"], t["serialization_format"], t["offered_qos_profiles"]),
        )
    for m in content["messages"]:
        db.execute(
            "INSERT INTO messages (topic_id, timestamp, data) VALUES (?, ?, ?)",
            (m["topic_id"], int(m["timestamp"]), base64.b64decode(m["data"])),
        )
    db.commit()
    db.close()
    stamps = [int(m["timestamp"]) for m in content["messages"]]
    topics = "".join(
        f"""    - topic_metadata:
        name: {t["name"]}
        type: {t["type"]}
        serialization_format: {t["serialization_format"]}
        offered_qos_profiles: ""
      message_count: {sum(1 for m in content["messages"] if m["topic_id"] == t["id"])}
"""
        for t in content["topics"]
    )
    with open(os.path.join(bag_dir, "metadata.yaml"), "w", encoding="utf-8") as f:
        f.write(
            f"""rosbag2_bagfile_information:
  version: 5
  storage_identifier: sqlite3
  duration:
    nanoseconds: {max(stamps) - min(stamps)}
  starting_time:
    nanoseconds_since_epoch: {min(stamps)}
  message_count: {len(stamps)}
  topics_with_message_count:
{topics}  compression_format: ""
  compression_mode: ""
  relative_file_paths:
    - bag_0.db3
  files:
    - path: bag_0.db3
      starting_time:
        nanoseconds_since_epoch: {min(stamps)}
      duration:
        nanoseconds: {max(stamps) - min(stamps)}
      message_count: {len(stamps)}
"""
        )
    print(f"{db_path}: {len(content['topics'])} topics, {len(stamps)} messages")


if __name__ == "__main__":
    main()
