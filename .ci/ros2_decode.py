"""Reads dronecine's MCAP files with an independent decoder: every CDR message through its
`ros2msg` schema, as the mcap project's ROS 2 support (the definitions and CDR that Foxglove
reads) decodes it. Fails on a schema it cannot parse, a message it cannot decode, a message
whose time disagrees with its log time, or a file with no CDR topic at all.

Usage: python ros2_decode.py FILE.mcap...
"""

import math
import sys
from collections import Counter

from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

# Topics whose message carries its own time (`t_s`) equal to the log time (a key frame on
# `/servo/state`: the time of the tick whose state it holds).
TIMED = {
    "/reference",
    "/actors",
    "/estimate",
    "/command",
    "/framing",
    "/servo/tick",
    "/servo/state",
}


def check(path):
    counts = Counter()
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        cdr_topics = {
            c.topic
            for c in reader.get_summary().channels.values()
            if c.message_encoding == "cdr"
        }
        if not cdr_topics:
            raise SystemExit(f"{path}: no CDR topic")
        for _schema, channel, message, decoded in reader.iter_decoded_messages(
            topics=sorted(cdr_topics)
        ):
            topic = channel.topic
            counts[topic] += 1
            if topic in TIMED and math.isfinite(decoded.t_s) and decoded.t_s >= 0:
                if round(decoded.t_s * 1e9) != message.log_time:
                    raise SystemExit(
                        f"{path}: {topic}: t_s {decoded.t_s} but log time {message.log_time} ns"
                    )
            if topic.startswith("/tf/"):
                last = decoded.transforms[-1]
                stamp = last.timestamp.sec * 1_000_000_000 + last.timestamp.nanosec
                if stamp != message.log_time:
                    raise SystemExit(f"{path}: {topic}: stamped {stamp}, logged {message.log_time}")
                if not math.isclose(
                    sum(x * x for x in (last.rotation.x, last.rotation.y, last.rotation.z, last.rotation.w)),
                    1.0,
                    abs_tol=1e-5,
                ):
                    raise SystemExit(f"{path}: {topic}: not a unit quaternion: {last.rotation}")
            if topic == "/measurement" and decoded.t_s * 1e9 > message.log_time + 1:
                raise SystemExit(f"{path}: /measurement captured after its tick")
    missing = cdr_topics - set(counts)
    if missing:
        raise SystemExit(f"{path}: no message decoded on {sorted(missing)}")
    summary = ", ".join(f"{t} {n}" for t, n in sorted(counts.items()))
    print(f"{path}: {sum(counts.values())} CDR messages decoded ({summary})")


for p in sys.argv[1:]:
    check(p)
