"""Named ports of the simulation's diagrams: listing them and wiring two diagrams by name."""

from __future__ import annotations

from pydrake.systems.framework import Diagram, DiagramBuilder, System

__all__ = ["NamedPorts", "connect_by_name", "input_port_names", "output_port_names"]


def input_port_names(system: System) -> list[str]:
    """Names of ``system``'s input ports, in port order."""
    return [system.get_input_port(i).get_name() for i in range(system.num_input_ports())]


def output_port_names(system: System) -> list[str]:
    """Names of ``system``'s output ports, in port order."""
    return [system.get_output_port(i).get_name() for i in range(system.num_output_ports())]


class NamedPorts:
    """The port listing of a record that holds a built ``diagram``."""

    diagram: Diagram

    def input_port_names(self) -> list[str]:
        """Names of the diagram's exported input ports."""
        return input_port_names(self.diagram)

    def output_port_names(self) -> list[str]:
        """Names of the diagram's exported output ports."""
        return output_port_names(self.diagram)


def connect_by_name(builder: DiagramBuilder, source: System, sink: System) -> list[str]:
    """Connects every input port of ``sink`` to the output port of ``source``
    with the same name, where there is one; both already in ``builder``.

    Returns:
        The names connected, in ``sink``'s port order.
    """
    outputs = set(output_port_names(source))
    connected = [name for name in input_port_names(sink) if name in outputs]
    for name in connected:
        builder.Connect(source.GetOutputPort(name), sink.GetInputPort(name))
    return connected
