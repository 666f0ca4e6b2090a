//! `quadctl`: command-line front end of the quadruped kinematics.

fn main() {
    println!("quadctl");
}
