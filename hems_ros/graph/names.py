"""Fingers, shoulder modules, node names and topics of the HEMS graph (dissertation chapter 6).

A graph lives in one namespace, ``/hems`` unless told otherwise (``hems up --namespace left``,
``ros2 run ... --ros-args -r __ns:=/left``), so that two hands share a domain: every topic and
service below takes it; the nodes take their own (``Node.get_namespace()``)."""

from __future__ import annotations

NAMESPACE = "/hems"
FINGERS = ("thumb_flexion", "thumb_abduction", "index", "middle", "ring", "little")
# Each shoulder module anchors two actuators and houses their two force sensors; the pairing
# follows the natural pairing deduced from chapter 6.
MODULES = {
    "thumb": ("thumb_flexion", "thumb_abduction"),
    "index_middle": ("index", "middle"),
    "ring_little": ("ring", "little"),
}
MODULE_OF = {finger: module for module, fingers in MODULES.items() for finger in fingers}
SUPERVISOR_SERVICES = ("enable", "disable", "estop", "reset")


def check_finger(finger: str) -> str:
    if finger not in FINGERS:
        raise ValueError(f"unknown finger {finger!r}: expected one of {', '.join(FINGERS)}")
    return finger


def parse_fingers(text: str) -> tuple[str, ...]:
    """A comma-separated finger list of the command line, or "all" (every finger, in
    FINGERS order)."""
    if text.strip() == "all":
        return FINGERS
    return tuple(check_finger(f.strip()) for f in text.split(","))


def check_module(module: str) -> str:
    if module not in MODULES:
        raise ValueError(
            f"unknown shoulder module {module!r}: expected one of {', '.join(MODULES)}"
        )
    return module


def check_namespace(text: str) -> str:
    """A graph namespace as the command line gives it ("left", "/left", "/lab/left"), made
    absolute; each token a ROS name token (letters, digits, underscores, not starting with a
    digit)."""
    tokens = [t for t in text.strip().split("/") if t]
    if not tokens or any(
        not t.replace("_", "a").isalnum() or not t.isascii() or t[0].isdigit() for t in tokens
    ):
        raise ValueError(
            f"namespace {text!r}: expected tokens of letters, digits and underscores, "
            "not starting with a digit, e.g. left or /lab/left"
        )
    return "/" + "/".join(tokens)


def topic(finger: str, stream: str, namespace: str = NAMESPACE) -> str:
    """Per-finger topic: duty, encoder, drive, wire_force, setpoint, controller_status, commands."""
    return f"{namespace.rstrip('/')}/{finger}/{stream}"


def sim_topic(finger: str, stream: str, namespace: str = NAMESPACE) -> str:
    """Simulation-only link (not available on hardware): state, wire_tension."""
    return f"{namespace.rstrip('/')}/sim/{finger}/{stream}"


def supervisor_status_topic(namespace: str = NAMESPACE) -> str:
    return f"{namespace.rstrip('/')}/supervisor/status"


def supervisor_commands_topic(namespace: str = NAMESPACE) -> str:
    return f"{namespace.rstrip('/')}/supervisor/commands"


def joint_states_topic(namespace: str = NAMESPACE) -> str:
    return f"{namespace.rstrip('/')}/joint_states"


def service(name: str, namespace: str = NAMESPACE) -> str:
    return f"{namespace.rstrip('/')}/supervisor/{name}"


SUPERVISOR_STATUS_TOPIC = supervisor_status_topic()
SUPERVISOR_COMMANDS_TOPIC = supervisor_commands_topic()
JOINT_STATES_TOPIC = joint_states_topic()
# shared by every graph of the domain: each status names its node, namespace included
DIAGNOSTICS_TOPIC = "/diagnostics"


def diagnostic_name(namespace: str, *parts: str) -> str:
    """Name of a node's status on /diagnostics: "hems/supervisor", "left/actuation_unit/index"."""
    return "/".join((namespace.strip("/"), *parts))


def node_names() -> list[tuple[str, str, dict[str, str]]]:
    """(executable, node name, parameters) of the 16 nodes of the full graph."""
    nodes = [("actuation_unit", f"actuation_unit_{f}", {"finger": f}) for f in FINGERS]
    nodes += [("shoulder_module", f"shoulder_module_{m}", {"module": m}) for m in MODULES]
    nodes += [("finger_controller", f"finger_controller_{f}", {"finger": f}) for f in FINGERS]
    nodes.append(("supervisor", "supervisor", {}))
    return nodes
