//! Proves the validation plumbing the other GPU tests rely on: a deliberate misuse must be reported, and so must
//! a leaked object. If these fail, a "0 validation messages" assertion elsewhere would prove nothing.

use ash::vk;
use volcast::gpu::resources::{record_readback, Buffer, Image, ImageDesc};
use volcast::gpu::sync::Access;
use volcast::gpu::{Gpu, GpuOptions};

fn validated_gpu() -> Gpu {
    Gpu::new(&GpuOptions {
        validation: true,
        ..Default::default()
    })
    .expect("Vulkan with the validation layer")
}

fn target(gpu: &Gpu) -> (Image, Buffer) {
    let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC;
    let image = Image::new(gpu, ImageDesc::d2(vk::Format::R8G8B8A8_UNORM, 8, 8, usage), "canary").expect("image");
    let buffer = Buffer::new(
        gpu,
        8 * 8 * 4,
        vk::BufferUsageFlags::TRANSFER_DST,
        gpu_allocator::MemoryLocation::GpuToCpu,
        "canary readback",
    )
    .expect("buffer");
    (image, buffer)
}

#[test]
fn a_wrong_image_layout_is_reported() {
    let gpu = validated_gpu();
    let (image, buffer) = target(&gpu);
    gpu.submit_and_wait(|cb| {
        // Claims the never-written image is a colour attachment: a layout mismatch the layer must catch.
        record_readback(&gpu, cb, &image, Access::ColorAttachmentWrite, &buffer);
    })
    .expect("submit");
    buffer.destroy(&gpu);
    image.destroy(&gpu);
    let problems = gpu.validation_problems();
    assert!(
        problems.iter().any(|p| p.text.contains("InvalidImageLayout")),
        "the validation layer missed a wrong image layout: {problems:#?}"
    );
}

/// Synchronization validation is live: a transfer that writes a buffer and a copy that reads it, recorded with no
/// barrier between them, is a read-after-write hazard the layer must name.
#[test]
fn a_missing_barrier_is_a_sync_hazard() {
    let gpu = validated_gpu();
    let buffer = |name: &str| {
        Buffer::new(
            &gpu,
            256,
            vk::BufferUsageFlags::TRANSFER_SRC | vk::BufferUsageFlags::TRANSFER_DST,
            gpu_allocator::MemoryLocation::GpuOnly,
            name,
        )
        .expect("buffer")
    };
    let (source, destination) = (buffer("hazard source"), buffer("hazard destination"));
    gpu.submit_and_wait(|cb| {
        let region = vk::BufferCopy::default().size(256);
        // SAFETY: both buffers are alive, TRANSFER_SRC|DST, 256 bytes, and `cb` is recording; the missing barrier
        // between the write and the read is the point of the test (a hazard, not undefined memory access).
        unsafe {
            gpu.device.cmd_fill_buffer(cb, source.raw, 0, 256, 0x5eed);
            gpu.device.cmd_copy_buffer(cb, source.raw, destination.raw, &[region]);
        }
    })
    .expect("submit");
    source.destroy(&gpu);
    destination.destroy(&gpu);
    let problems = gpu.validation_problems();
    assert!(
        problems.iter().any(|p| p.text.contains("SYNC-HAZARD-READ-AFTER-WRITE")),
        "synchronization validation missed a read-after-write hazard: {problems:#?}"
    );
}

#[test]
fn a_correct_readback_is_clean() {
    let gpu = validated_gpu();
    let (image, buffer) = target(&gpu);
    gpu.submit_and_wait(|cb| {
        record_readback(&gpu, cb, &image, Access::Undefined, &buffer);
    })
    .expect("submit");
    buffer.destroy(&gpu);
    image.destroy(&gpu);
    let log = gpu.log.clone();
    drop(gpu);
    assert!(log.problems().is_empty(), "{:#?}", log.problems());
}

#[test]
fn a_leaked_image_is_reported_at_shutdown() {
    let gpu = validated_gpu();
    let (image, buffer) = target(&gpu);
    buffer.destroy(&gpu);
    std::mem::forget(image);
    let log = gpu.log.clone();
    drop(gpu);
    let problems = log.problems();
    assert!(
        problems
            .iter()
            .any(|p| p.text.contains("leaked GPU allocation 'canary'")),
        "the allocator leak report is missing: {problems:#?}"
    );
    assert!(
        problems.iter().any(|p| p.text.contains("VkImage")),
        "the layer's leak report is missing: {problems:#?}"
    );
}
