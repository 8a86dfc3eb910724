#!/usr/bin/env python3
"""A fake ArduCopter on pymavlink, for the backend's flight test over UDP loopback.

It listens on 127.0.0.1 (a free port, printed first as {"port": N}) and answers
every address that sent to it:
- HEARTBEAT, SYS_STATUS (battery 90 %), EXTENDED_SYS_STATE, ATTITUDE (yaw 0.3 rad),
  LOCAL_POSITION_NED (its height) and GIMBAL_DEVICE_ATTITUDE_STATUS every 50 ms;
- PARAM_REQUEST_READ from its parameter table (`right` or `wrong`, the first argument;
  `wrong` is an older firmware's, with GPS_TYPE and no GPS1_TYPE);
- COMMAND_LONG with COMMAND_ACK: DO_SET_MODE sets the mode, COMPONENT_ARM_DISARM arms
  (in GUIDED_NOGPS only) or disarms, SET_MESSAGE_INTERVAL is accepted, REQUEST_MESSAGE of
  GPS_GLOBAL_ORIGIN answers with its origin once it has one, others unsupported;
- SET_ATTITUDE_TARGET in GUIDED_NOGPS moves its height at the climb rate the thrust asks
  for (WPNAV_SPEED_UP 250, WPNAV_SPEED_DN 150 cm/s); LAND descends at 1 m/s and disarms on
  the ground; GIMBAL_MANAGER_SET_PITCHYAW turns its gimbal;
- after a VISION_POSITION_ESTIMATE: "EKF3 IMU0 is using external nav data"; as
  ArduPilot's EKF, a SET_GPS_GLOBAL_ORIGIN before the first VISION_POSITION_ESTIMATE is
  dropped, one after it is the origin, confirmed with GPS_GLOBAL_ORIGIN.
Each message it receives prints as {"rx": TYPE, "fields": {...}}. A line "failsafe" on its
standard input switches it to LAND by itself; it ends when its standard input closes.
"""
import json
import math
import os
import select
import sys
import time

os.environ["MAVLINK20"] = "1"
from pymavlink import mavutil  # noqa: E402

GUIDED_NOGPS, LAND = 20, 9
YAW = 0.3
PARAMS = {
    "right": {
        "VISO_TYPE": 1, "GPS1_TYPE": 0, "EK3_SRC1_POSXY": 6, "EK3_SRC1_VELXY": 6,
        "EK3_SRC1_POSZ": 6, "EK3_SRC1_VELZ": 6, "GUID_OPTIONS": 0,
        "WPNAV_SPEED_UP": 250, "WPNAV_SPEED_DN": 150, "ANGLE_MAX": 3000,
        "ATC_RATE_Y_MAX": 0, "GUID_TIMEOUT": 3,
    },
    "wrong": {
        "VISO_TYPE": 0, "GPS_TYPE": 1, "EK3_SRC1_POSXY": 6, "EK3_SRC1_VELXY": 6,
        "EK3_SRC1_POSZ": 1, "EK3_SRC1_VELZ": 6, "GUID_OPTIONS": 8,
        "WPNAV_SPEED_UP": 250, "WPNAV_SPEED_DN": 150, "ANGLE_MAX": 3000,
        "ATC_RATE_Y_MAX": 0, "GUID_TIMEOUT": 3,
    },
}


def clean(value):
    if isinstance(value, float) and math.isnan(value):
        return "NaN"
    if isinstance(value, bytes):
        return value.decode("utf-8", "replace").rstrip("\0")
    if isinstance(value, (list, tuple)):
        return [clean(v) for v in value]
    return value


def quaternion(roll, pitch, yaw):
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return [cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy]


class Vehicle:
    def __init__(self, link, params):
        self.link, self.mav, self.params = link, link.mav, params
        self.mode, self.armed, self.height = 0, False, 0.0
        self.climb, self.climb_until = 0.0, 0.0
        self.gimbal_pitch = 0.0
        self.origin = self.vision = self.said_nav = False
        self.t0 = time.time()

    def ms(self):
        return int((time.time() - self.t0) * 1000)

    def text(self, severity, text):
        self.mav.statustext_send(severity, text.encode())

    def handle(self, msg):
        kind = msg.get_type()
        fields = {k: clean(v) for k, v in msg.to_dict().items() if k != "mavpackettype"}
        print(json.dumps({"rx": kind, "fields": fields}), flush=True)
        handler = getattr(self, "on_" + kind.lower(), None)
        if handler:
            handler(msg)

    def on_param_request_read(self, msg):
        name = msg.param_id if isinstance(msg.param_id, str) else msg.param_id.decode()
        if name in self.params:
            self.mav.param_value_send(name.encode(), float(self.params[name]), 9,
                                      len(self.params), 65535)

    def on_command_long(self, msg):
        result = 0
        if msg.command == 176:
            self.mode = int(msg.param2)
        elif msg.command == 400 and msg.param1 == 1:
            if self.mode == GUIDED_NOGPS:
                self.armed = True
            else:
                result = 2
                self.text(3, "Arm: Mode not armable")
        elif msg.command == 400:
            self.armed = False
        elif msg.command == 512 and int(msg.param1) == 49:
            if self.origin:
                self.send_origin()
        elif msg.command != 511:
            result = 3
        self.mav.command_ack_send(msg.command, result)

    def on_set_attitude_target(self, msg):
        up, down = self.params["WPNAV_SPEED_UP"] / 100, self.params["WPNAV_SPEED_DN"] / 100
        t = msg.thrust
        self.climb = (t - 0.5) * 2 * (up if t >= 0.5 else down)
        self.climb_until = time.time() + 1.0

    def on_gimbal_manager_set_pitchyaw(self, msg):
        self.gimbal_pitch = msg.pitch

    def on_set_gps_global_origin(self, msg):
        # As ArduPilot's EKF: an origin that comes before it is initialised (by the external
        # navigation) is dropped.
        if self.vision:
            self.origin = (msg.latitude, msg.longitude, msg.altitude)
            self.send_origin()

    def send_origin(self):
        lat, lon, alt = self.origin
        self.mav.gps_global_origin_send(lat, lon, alt, self.ms() * 1000)

    def on_vision_position_estimate(self, _msg):
        self.vision = True

    def step(self, dt):
        if self.armed and self.mode == GUIDED_NOGPS and time.time() < self.climb_until:
            self.height = max(0.0, self.height + self.climb * dt)
        elif self.armed and self.mode == LAND:
            self.height -= 1.0 * dt
            if self.height <= 0.0:
                self.height, self.armed = 0.0, False
                self.text(6, "Disarming motors")
        if self.vision and not self.said_nav:
            self.said_nav = True
            self.text(6, "EKF3 IMU0 is using external nav data")

    def report(self):
        m = self.mav
        m.heartbeat_send(2, 3, (128 if self.armed else 0) | 1, self.mode, 4)
        m.sys_status_send(0, 0, 0, 0, 12400, 1000, 90, 0, 0, 0, 0, 0, 0)
        landed = 2 if self.height > 0.05 else 1
        m.extended_sys_state_send(0, landed)
        m.attitude_send(self.ms(), 0.0, 0.0, YAW, 0.0, 0.0, 0.0)
        m.local_position_ned_send(self.ms(), 0.0, 0.0, -self.height, 0.0, 0.0, 0.0)
        m.gimbal_device_attitude_status_send(0, 0, self.ms(), 12,
                                             quaternion(0.0, self.gimbal_pitch, 0.0),
                                             0.0, 0.0, 0.0, 0)


def main():
    link = mavutil.mavlink_connection("udpin:127.0.0.1:0", source_system=1,
                                      source_component=1, dialect="ardupilotmega")
    print(json.dumps({"port": link.port.getsockname()[1]}), flush=True)
    vehicle = Vehicle(link, PARAMS[sys.argv[1]])
    last = next_report = time.time()
    while True:
        ready, _, _ = select.select([link.port, sys.stdin], [], [], 0.01)
        if link.port in ready:
            while True:
                msg = link.recv_match(blocking=False)
                if msg is None:
                    break
                vehicle.handle(msg)
        if sys.stdin in ready:
            line = sys.stdin.readline()
            if not line:
                return
            if line.strip() == "failsafe":
                vehicle.mode = LAND
                vehicle.text(2, "Battery failsafe")
        now = time.time()
        vehicle.step(now - last)
        last = now
        if now >= next_report and link.clients:
            vehicle.report()
            next_report = now + 0.05


if __name__ == "__main__":
    main()
