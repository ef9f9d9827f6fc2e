"""CAN ultrasonic sonar board (Neobotix USBoard style): protocol as a DBC file and a pure codec."""
