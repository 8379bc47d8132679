//! The viewer's state and its egui user interface: the state (plain data), the settings panel, the overlay and
//! input of the 3D view, and the keyboard shortcuts.

mod drag_split;
mod keys;
mod overlay;
mod panel;
pub mod rects;
mod state;
mod tf_panel;

pub use drag_split::drag_cut;
pub use keys::{next_lower, shortcuts, take_tab_presses};
pub use overlay::{box_corners, project, side_labels, view_overlay};
pub use panel::settings_panel;
pub use state::{UiAction, ViewerState, AUTO_ROTATE_DEG_PER_S};
