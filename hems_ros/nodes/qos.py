"""QoS of the graph: sensor streams best effort, commands reliable, supervisor status transient
local; the controller status (heartbeat) as the sensor streams."""

from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

SENSOR = QoSProfile(depth=10, history=HistoryPolicy.KEEP_LAST, reliability=ReliabilityPolicy.BEST_EFFORT)
COMMAND = QoSProfile(depth=10, history=HistoryPolicy.KEEP_LAST, reliability=ReliabilityPolicy.RELIABLE)
STATUS = QoSProfile(depth=1, history=HistoryPolicy.KEEP_LAST, reliability=ReliabilityPolicy.RELIABLE,
                    durability=DurabilityPolicy.TRANSIENT_LOCAL)
# Writer and every reader of /hems/<finger>/controller_status take this (a reliable reader does
# not match the best-effort writer). Best effort: each status supersedes the last within 20 ms,
# and a reliable reader held every later status back behind a lost one until the writer's next
# heartbeat repaired it, about 200 ms at 50 Hz; the supervisor then saw the controller as dead
# (processes joining the domain, benchmarks/bench_graph_joins.py, tests/graph/README.md).
CONTROLLER_STATUS = SENSOR
# What a node was commanded (hems_msgs/CommandRecord): every record reaches a recorder that has
# matched the node, and one that joins later still gets the last hundred.
COMMAND_LOG = QoSProfile(depth=100, history=HistoryPolicy.KEEP_LAST, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
# /hems/joint_states is for tools outside the graph (RViz, plotting scripts), whose readers are
# reliable by default and do not match a best-effort writer; a reliable writer serves both.
JOINT_STATES = COMMAND
