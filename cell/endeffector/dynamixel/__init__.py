"""The end-effector on Dynamixel servos (Protocol 2.0), and an emulated bus to try it on.

- `registers`: control tables of the supported models (data only).
- `config`: `DynamixelConfig`, loaded from `robots/throwing_ee/dynamixel.yaml`.
- `bus`: `DynamixelBus`, dynamixel-sdk with retries and typed errors.
- `driver`: `DynamixelEndEffector`, the `EndEffector` back-end.
- `emulator`: `EmulatedBus`, Protocol 2.0 servos and the spool on a pseudo-terminal.
"""

from cell.endeffector.dynamixel.config import DynamixelConfig, load_config
from cell.endeffector.dynamixel.driver import DynamixelEndEffector
from cell.endeffector.dynamixel.emulator import EmulatedBus

__all__ = ["DynamixelConfig", "DynamixelEndEffector", "EmulatedBus", "load_config"]
