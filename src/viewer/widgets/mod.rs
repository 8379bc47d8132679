//! The viewer's egui user interface. Every widget edits the [`Model`](crate::viewer::model::Model) (or the part
//! of it it shows) through an egui `Ui`, and asks for anything beyond that — loading, files, captures — with a
//! [`UiAction`](crate::viewer::model::actions::UiAction). Widgets know nothing of the app or the presenter: the
//! slice views get their images through [`slice_view::SliceImages`].
//!
//! [`layout::frame_ui`] is one frame's whole UI: the settings panel ([`panel`]) and the view area, the 3D view's
//! overlay ([`overlay`]: boxes, gizmos, clipping plane, colour bar) alone or beside the slice views.

pub mod clicks;
pub mod clip_plane;
pub mod colorbar;
pub mod keys;
pub mod layout;
pub mod light_gizmo;
pub mod marks;
pub mod orientation;
pub mod overlay;
pub mod panel;
pub mod rects;
pub mod ruler;
pub mod screen;
pub mod shown_slice;
pub mod slice_view;
pub mod tf_editor;
