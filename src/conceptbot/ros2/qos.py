"""The quality of service of the node's topics, shared by the node and its clients.

All three are reliable with a history of :data:`~conceptbot.ros2.protocol.QOS_DEPTH` messages. The
replies (``~/progress``, ``~/result``) are also *transient local*: the node keeps the last ones for
a subscriber it discovers late. Discovery is not symmetric: a client can see the node's subscription
(and send its request) before the node's publisher has matched the client's subscription, and a
volatile reply sent in that gap reaches nobody (in about 1 of 15 runs of this package's tests,
before the replies were made transient local). A client that subscribes transient local gets such
replies once the match completes, and also the last replies to other requests: it keeps those with
its own id. Requests stay volatile, so a node that restarts never plans an old request again.
"""

from __future__ import annotations

from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

from conceptbot.ros2.protocol import QOS_DEPTH

REQUESTS = QoSProfile(depth=QOS_DEPTH, reliability=ReliabilityPolicy.RELIABLE)
"""``~/request``: reliable, volatile."""

REPLIES = QoSProfile(
    depth=QOS_DEPTH, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
)
"""``~/progress`` and ``~/result``: reliable, transient local (a volatile subscriber works too)."""
