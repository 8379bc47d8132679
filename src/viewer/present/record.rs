//! What a frame records after the march: the swapchain image cleared, the view image blitted into the view's place
//! in it ([`view_pixels`]) and egui drawn over it (the copies for captures are in [`super::readback`]).

use super::screen::Acquired;
use crate::gpu::resources::Image;
use crate::gpu::sync::{image_barrier, memory_barrier, Access, COLOR_LAYERS, COLOR_RANGE};
use crate::viewer::ViewerError;
use ash::vk;

/// The view image's rendered size and where it goes in the swapchain image (pixels).
#[derive(Clone, Copy, Debug)]
pub(super) struct Blit {
    /// The frame rendered: at full detail the view's size, at reduced detail smaller (then upscaled).
    pub(super) rendered: vk::Extent2D,
    pub(super) offset: vk::Offset2D,
    pub(super) size: vk::Extent2D,
}

/// The volume view's place in the swapchain image, in pixels: the central area egui left free (`rect`, points;
/// the whole window before the first layout), clamped to the image.
pub fn view_pixels(
    rect: Option<egui::Rect>,
    pixels_per_point: f32,
    extent: vk::Extent2D,
) -> (vk::Offset2D, vk::Extent2D) {
    let (w, h) = (extent.width as f32, extent.height as f32);
    let r = rect
        .map(|r| {
            let ppp = pixels_per_point.max(0.1);
            egui::Rect::from_min_max(
                egui::pos2(
                    (r.min.x * ppp).round().clamp(0.0, w - 1.0),
                    (r.min.y * ppp).round().clamp(0.0, h - 1.0),
                ),
                egui::pos2(
                    (r.max.x * ppp).round().clamp(1.0, w),
                    (r.max.y * ppp).round().clamp(1.0, h),
                ),
            )
        })
        .unwrap_or(egui::Rect::from_min_max(egui::Pos2::ZERO, egui::pos2(w, h)));
    let width = (r.width() as u32).max(1);
    let height = (r.height() as u32).max(1);
    (
        vk::Offset2D {
            x: r.min.x as i32,
            y: r.min.y as i32,
        },
        vk::Extent2D { width, height },
    )
}

/// Clears the swapchain image `target` (just acquired) and blits the view image into its place; the view was last
/// accessed as `view.1` (marched just now, or read by the last frame's transfers). Leaves `target` ready to be drawn
/// on as a colour attachment.
pub(super) fn record_blit(
    dev: &ash::Device,
    cb: vk::CommandBuffer,
    (view, view_was): (&Image, Access),
    target: vk::Image,
    blit: Blit,
) {
    // After a march its writes must be done; shown again, the last frame's reads need nothing before these reads.
    if view_was != Access::TransferRead {
        image_barrier(dev, cb, view.raw, view_was, Access::TransferRead);
    }
    image_barrier(dev, cb, target, Access::SwapchainAcquired, Access::TransferWrite);
    // Cleared first: the panel covers the rest, but not while it is hidden or being laid out.
    let black = vk::ClearColorValue {
        float32: [0.0, 0.0, 0.0, 1.0],
    };
    // SAFETY: the image is in TRANSFER_DST layout.
    unsafe {
        dev.cmd_clear_color_image(
            cb,
            target,
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            &black,
            &[COLOR_RANGE],
        )
    };
    memory_barrier(dev, cb, Access::TransferWrite, Access::TransferWrite);
    let corner = vk::Offset3D {
        x: blit.rendered.width as i32,
        y: blit.rendered.height as i32,
        z: 1,
    };
    let dst_corner = vk::Offset3D {
        x: blit.offset.x + blit.size.width as i32,
        y: blit.offset.y + blit.size.height as i32,
        z: 1,
    };
    let dst_origin = vk::Offset3D {
        x: blit.offset.x,
        y: blit.offset.y,
        z: 0,
    };
    let layers = COLOR_LAYERS;
    let region = vk::ImageBlit::default()
        .src_subresource(layers)
        .src_offsets([vk::Offset3D::default(), corner])
        .dst_subresource(layers)
        .dst_offsets([dst_origin, dst_corner]);
    let filter = if blit.rendered.width == blit.size.width {
        vk::Filter::NEAREST
    } else {
        vk::Filter::LINEAR
    };
    // SAFETY: both images are in the layouts named and the regions lie inside them. At full detail the sizes
    // match and the blit only swizzles RGBA to BGRA; at reduced detail it also upscales (linear).
    unsafe {
        dev.cmd_blit_image(
            cb,
            view.raw,
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            target,
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            &[region],
            filter,
        )
    };
    image_barrier(dev, cb, target, Access::TransferWrite, Access::ColorAttachmentWrite);
}

/// egui's shapes over the whole swapchain image `target` (`extent`); `target` is left a colour attachment.
pub(super) fn record_egui(
    dev: &ash::Device,
    cb: vk::CommandBuffer,
    renderer: &mut super::EguiRenderer,
    target: &Acquired,
    extent: vk::Extent2D,
    pixels_per_point: f32,
    primitives: &[egui::ClippedPrimitive],
) -> Result<(), ViewerError> {
    let attachment = [vk::RenderingAttachmentInfo::default()
        .image_view(target.view)
        .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
        .load_op(vk::AttachmentLoadOp::LOAD)
        .store_op(vk::AttachmentStoreOp::STORE)];
    let rendering = vk::RenderingInfo::default()
        .render_area(vk::Rect2D {
            offset: vk::Offset2D::default(),
            extent,
        })
        .layer_count(1)
        .color_attachments(&attachment);
    // SAFETY: the swapchain image is a colour attachment now.
    unsafe { dev.cmd_begin_rendering(cb, &rendering) };
    renderer
        .cmd_draw(cb, extent, pixels_per_point, primitives)
        .map_err(|e| ViewerError::Other(format!("egui draw: {e}")))?;
    // SAFETY: rendering was begun above.
    unsafe { dev.cmd_end_rendering(cb) };
    Ok(())
}
