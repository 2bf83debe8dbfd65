"""Fingers, shoulder modules, node names and topics of the HEMS graph (dissertation chapter 6)."""

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
    """A comma-separated finger list of the command line, or "all" (every finger, in FINGERS order)."""
    if text.strip() == "all":
        return FINGERS
    return tuple(check_finger(f.strip()) for f in text.split(","))


def check_module(module: str) -> str:
    if module not in MODULES:
        raise ValueError(f"unknown shoulder module {module!r}: expected one of {', '.join(MODULES)}")
    return module


def topic(finger: str, stream: str) -> str:
    """Per-finger topic: duty, encoder, wire_force, setpoint, controller_status, commands."""
    return f"{NAMESPACE}/{finger}/{stream}"


def sim_topic(finger: str, stream: str) -> str:
    """Simulation-only link (not available on hardware): state, wire_tension."""
    return f"{NAMESPACE}/sim/{finger}/{stream}"


SUPERVISOR_STATUS_TOPIC = f"{NAMESPACE}/supervisor/status"
SUPERVISOR_COMMANDS_TOPIC = f"{NAMESPACE}/supervisor/commands"
JOINT_STATES_TOPIC = f"{NAMESPACE}/joint_states"
DIAGNOSTICS_TOPIC = "/diagnostics"


def service(name: str) -> str:
    return f"{NAMESPACE}/supervisor/{name}"


def node_names() -> list[tuple[str, str, dict[str, str]]]:
    """(executable, node name, parameters) of the 16 nodes of the full graph."""
    nodes = [("actuation_unit", f"actuation_unit_{f}", {"finger": f}) for f in FINGERS]
    nodes += [("shoulder_module", f"shoulder_module_{m}", {"module": m}) for m in MODULES]
    nodes += [("finger_controller", f"finger_controller_{f}", {"finger": f}) for f in FINGERS]
    nodes.append(("supervisor", "supervisor", {}))
    return nodes
