//! A drag-and-drop source for the viewer tests: drops a file on a window by the XDND protocol (version 5), as a
//! file manager does, so the window's own XDND handling (winit's) turns it into a `DroppedFile` event.
//!
//! The exchange (<https://www.freedesktop.org/wiki/Specifications/XDND/>): the source owns the `XdndSelection`,
//! sends `XdndEnter` with its type `text/uri-list` and `XdndPosition` over the window; the target asks for the
//! selection (a `SelectionRequest` the source answers by writing the URI list onto the target's property) and
//! replies `XdndStatus`. A second position round trip makes sure the target has read the data before
//! `XdndDrop`; the target ends with `XdndFinished`.

use std::path::Path;
use std::time::{Duration, Instant};
use x11rb::connection::Connection;
use x11rb::protocol::xproto::{
    AtomEnum, ClientMessageEvent, ConnectionExt as _, CreateWindowAux, EventMask, PropMode, SelectionNotifyEvent,
    WindowClass, SELECTION_NOTIFY_EVENT,
};
use x11rb::protocol::Event;
use x11rb::rust_connection::RustConnection;
use x11rb::wrapper::ConnectionExt as _;
use x11rb::CURRENT_TIME;

/// Drops `file` on `window` (an X window id) at window position (x, y); returns the target's answer in
/// `XdndFinished` (whether it accepted the drop).
pub fn drop_file(display: &str, window: u32, (x, y): (i16, i16), file: &Path) -> Result<bool, String> {
    let (conn, screen) = x11rb::connect(Some(display)).map_err(|e| format!("connect to {display}: {e}"))?;
    let root = conn.setup().roots[screen].root;
    let [aware, enter, position, status, drop, finished, selection, uri_list, copy] = [
        "XdndAware",
        "XdndEnter",
        "XdndPosition",
        "XdndStatus",
        "XdndDrop",
        "XdndFinished",
        "XdndSelection",
        "text/uri-list",
        "XdndActionCopy",
    ]
    .map(|name| intern(&conn, name));
    let (aware, enter, position, status, drop, finished, selection, uri_list, copy) = (
        aware?, enter?, position?, status?, drop?, finished?, selection?, uri_list?, copy?,
    );
    let x11 = |err: x11rb::errors::ConnectionError| err.to_string();
    // The target must say it speaks XDND, and which version.
    let version = conn
        .get_property(false, window, aware, AtomEnum::ATOM, 0, 1)
        .map_err(|err| err.to_string())?
        .reply()
        .map_err(|err| err.to_string())?
        .value32()
        .and_then(|mut v| v.next())
        .ok_or_else(|| format!("window {window:#x} has no XdndAware property"))?
        .min(5);
    let source = conn.generate_id().map_err(|err| err.to_string())?;
    conn.create_window(
        0,
        source,
        root,
        0,
        0,
        1,
        1,
        0,
        WindowClass::INPUT_OUTPUT,
        0,
        &CreateWindowAux::new(),
    )
    .map_err(x11)?;
    conn.set_selection_owner(source, selection, CURRENT_TIME).map_err(x11)?;
    let uri = format!("file://{}\r\n", file.display());
    let send = |kind: u32, data: [u32; 5]| -> Result<(), String> {
        let msg = ClientMessageEvent::new(32, window, kind, data);
        conn.send_event(false, window, EventMask::NO_EVENT, msg).map_err(x11)?;
        conn.flush().map_err(x11)
    };
    let packed = root_position(&conn, window, x, y)?;
    send(enter, [source, version << 24, uri_list, 0, 0])?;
    // Serve the selection until the target answers a position; twice, so that the data request of the first is
    // answered and read before the drop.
    for _ in 0..2 {
        send(position, [source, 0, packed, CURRENT_TIME, copy])?;
        let answer = serve_until(&conn, source, status, &uri)?;
        if answer[1] & 1 == 0 {
            return Err(format!("window {window:#x} refused the drag of {}", file.display()));
        }
    }
    send(drop, [source, 0, CURRENT_TIME, 0, 0])?;
    let done = serve_until(&conn, source, finished, &uri)?;
    let _ = conn.destroy_window(source);
    let _ = conn.flush();
    Ok(version < 5 || done[1] & 1 == 1)
}

fn intern(conn: &RustConnection, name: &str) -> Result<u32, String> {
    let reply = conn
        .intern_atom(false, name.as_bytes())
        .map_err(|err| format!("{name}: {err}"))?;
    Ok(reply.reply().map_err(|err| format!("{name}: {err}"))?.atom)
}

/// The window position (x, y) in root coordinates, packed as XDND wants it (x in the high 16 bits).
fn root_position(conn: &RustConnection, window: u32, x: i16, y: i16) -> Result<u32, String> {
    let root = conn.setup().roots[0].root;
    let t = conn
        .translate_coordinates(window, root, x, y)
        .map_err(|err| err.to_string())?
        .reply()
        .map_err(|err| err.to_string())?;
    Ok((u32::from(t.dst_x as u16) << 16) | u32::from(t.dst_y as u16))
}

/// Handles events on the source window until a client message of type `kind` arrives (its data returned),
/// answering selection requests with `uri`. Gives up after 30 s.
fn serve_until(conn: &RustConnection, source: u32, kind: u32, uri: &str) -> Result<[u32; 5], String> {
    let deadline = Instant::now() + Duration::from_secs(30);
    while Instant::now() < deadline {
        let Some(event) = conn.poll_for_event().map_err(|err| err.to_string())? else {
            std::thread::sleep(Duration::from_millis(5));
            continue;
        };
        match event {
            Event::ClientMessage(m) if m.window == source && m.type_ == kind => return Ok(m.data.as_data32()),
            Event::SelectionRequest(r) => {
                conn.change_property8(PropMode::REPLACE, r.requestor, r.property, r.target, uri.as_bytes())
                    .map_err(|err| err.to_string())?;
                let notify = SelectionNotifyEvent {
                    response_type: SELECTION_NOTIFY_EVENT,
                    sequence: 0,
                    time: r.time,
                    requestor: r.requestor,
                    selection: r.selection,
                    target: r.target,
                    property: r.property,
                };
                conn.send_event(false, r.requestor, EventMask::NO_EVENT, notify)
                    .map_err(|err| err.to_string())?;
                conn.flush().map_err(|err| err.to_string())?;
            }
            _ => {}
        }
    }
    Err("the drop target did not answer within 30 s".into())
}
