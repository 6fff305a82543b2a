//! What to tell a user who may not open a device, in one place for the errors that refuse
//! the device and the device listing that warns about it.

/// How to get access to a serial port on Linux, said wherever access is denied.
pub const SERIAL_PERMISSION_FIX: &str = "add yourself to the group that owns the port \
     (usually 'dialout': sudo usermod -aG dialout $USER, then log out and in again) or install \
     data/udev/60-metamer.rules (see README, 'Linux permissions')";

/// How to get access to a USB or HID instrument on Linux.
pub const USB_PERMISSION_FIX: &str = "install the udev rules: sudo cp data/udev/60-metamer.rules \
     /etc/udev/rules.d/ && sudo udevadm control --reload && sudo udevadm trigger, then unplug \
     and replug the instrument (see README, 'Linux permissions')";
