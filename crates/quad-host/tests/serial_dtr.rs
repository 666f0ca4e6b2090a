//! Opening a port leaves DTR asserted when the port is closed (`HUPCL` cleared), so that the
//! next open makes no edge on a Mega's reset line: checked on a pseudo-terminal, whose termios
//! the kernel keeps like a real port's.

#![cfg(unix)]

use nix::sys::termios::{tcgetattr, tcsetattr, ControlFlags, SetArg};
use quad_host::link::serial::SerialLink;
use serialport::{SerialPort, TTYPort};
use std::os::unix::io::AsRawFd;

#[test]
fn opening_a_port_clears_hupcl() {
    let (_master, slave) = TTYPort::pair().expect("a pty pair");
    let path = slave.name().expect("the slave's path");
    let fd = slave.as_raw_fd();
    let mut t = tcgetattr(fd).expect("termios");
    t.control_flags.insert(ControlFlags::HUPCL);
    tcsetattr(fd, SetArg::TCSANOW, &t).expect("HUPCL set");
    assert!(tcgetattr(fd)
        .expect("termios")
        .control_flags
        .contains(ControlFlags::HUPCL));
    let link = SerialLink::open(&path, 115_200).expect("the port opens");
    assert!(!tcgetattr(fd)
        .expect("termios")
        .control_flags
        .contains(ControlFlags::HUPCL));
    drop(link);
}
