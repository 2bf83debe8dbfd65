"""QoS of the graph: sensor streams, duty commands and the statuses best effort (each supersedes
the last within a period or two); setpoints and command records reliable."""

from rclpy.qos import (
    DurabilityPolicy,
    HistoryPolicy,
    QoSProfile,
    ReliabilityPolicy,
)

SENSOR = QoSProfile(
    depth=10, history=HistoryPolicy.KEEP_LAST, reliability=ReliabilityPolicy.BEST_EFFORT
)
COMMAND = QoSProfile(
    depth=10, history=HistoryPolicy.KEEP_LAST, reliability=ReliabilityPolicy.RELIABLE
)
# The supervisor's status, every 20 ms: the units' permission to heat lapses 35 ms after the
# last one (supervisor_timeout_s), so a stopped or killed supervisor stops the heating within
# that. Best effort, as the sensor streams: each status supersedes the last, a new reader has
# the next within 20 ms, and a reliable writer drew an acknowledgement from each of its dozen
# readers for each status, waking their event threads and the supervisor's listener.
STATUS = QoSProfile(
    depth=1, history=HistoryPolicy.KEEP_LAST, reliability=ReliabilityPolicy.BEST_EFFORT
)
# A tool's reader that only wants each stream's newest message (`hems status`), taken when it
# looks: best effort matches every writer of the graph.
LATEST = STATUS
# The same statuses for a unit, which takes them in a batch at its tick and runs its permission
# from each one's time: kept to one, a late tick (a busy host) that found two took only the
# newer, and the heating paused over the gap the older one had covered.
STATUS_EACH = QoSProfile(
    depth=10, history=HistoryPolicy.KEEP_LAST, reliability=ReliabilityPolicy.BEST_EFFORT
)
# Duty commands: each supersedes the last within one control period, and the unit's watchdog
# stops the heating after three periods without one, so a lost command needs no repair. A
# reliable writer kept each in a history and traded heartbeats and acknowledgements with the
# unit and the recorder for nothing (docs/design.md). A reliable writer (a test's, a tool's)
# still matches the units' best-effort readers.
DUTY = SENSOR
# Writer and every reader of /hems/<finger>/controller_status take this (a reliable reader does
# not match the best-effort writer). Best effort: each status supersedes the last within 20 ms,
# and a reliable reader held every later status back behind a lost one until the writer's next
# heartbeat repaired it, about 200 ms at 50 Hz; the supervisor then saw the controller as dead
# (processes joining the domain, benchmarks/bench_graph_joins.py, docs/design.md).
CONTROLLER_STATUS = SENSOR
# What a node was commanded (hems_msgs/CommandRecord): every record reaches a recorder that has
# matched the node, and one that joins later still gets the last hundred.
COMMAND_LOG = QoSProfile(
    depth=100,
    history=HistoryPolicy.KEEP_LAST,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)
# /hems/joint_states is for tools outside the graph (RViz, plotting scripts), whose readers are
# reliable by default and do not match a best-effort writer; a reliable writer serves both.
JOINT_STATES = COMMAND
