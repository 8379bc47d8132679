//! Every compositing mode on N ranks equals one process: shading and iso-surfaces (ordered blend), MIP and MinIP
//! (IceT's depth test on the value), average (sums and counts added).

use super::compare::same_image;
use super::ct_head;

#[test]
fn shaded_emission_with_the_gradient_texture() {
    same_image(
        "shaded",
        ct_head(),
        &["--shading", "--gradient-texture", "--azimuth", "-40"],
        &[4],
    );
}

#[test]
fn iso_surfaces_shaded() {
    same_image(
        "iso",
        ct_head(),
        &["--mode", "iso", "--iso", "45%", "--shading", "--azimuth", "150"],
        &[4],
    );
}

#[test]
fn maximum_and_minimum_intensity_projections() {
    same_image(
        "mip",
        ct_head(),
        &["--mode", "mip", "--azimuth", "80", "--elevation", "10"],
        &[4],
    );
    same_image("minip", ct_head(), &["--mode", "minip", "--window", "20%,90%"], &[2]);
}

#[test]
fn the_average_of_all_visible_samples() {
    same_image("average", ct_head(), &["--mode", "average", "--azimuth", "-100"], &[4]);
}
