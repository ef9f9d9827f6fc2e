"""The onboard daemon: the hal lifecycle, the control loop with the arbiter, the map kept on
disk, and the robot's side of the link. I/O lives here, never in ``tslam.core``."""
