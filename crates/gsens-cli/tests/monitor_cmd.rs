//! `gsens import gnss-sdr-monitor` over the loopback: the datagrams of a real
//! GNSS-SDR 0.0.17 monitor capture (gsens-gnss-sdr's fixture) sent to it,
//! plus garbage; it stops on its idle timeout and writes `tracking.csv` on
//! the 20 ms grid and the datagrams as received. A smoke test: a busy
//! machine may drop datagrams on the loopback, so what was received is
//! checked against what was sent, not counted exactly (the recording loop,
//! every datagram counted and kept, is gsens-live's tests/monitor.rs, on
//! datagrams given without a socket).

mod common;

use common::{s, temp_dir};

use std::io::{BufRead, BufReader};
use std::net::UdpSocket;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use gsens_gnss_sdr::monitor::split_capture;

fn fixture() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../gsens-gnss-sdr/tests/fixtures/monitor")
}

#[test]
fn records_a_live_stream_until_idle() {
    let d = temp_dir("monitor-cmd");
    let (out, raw) = (d.join("tracking.csv"), d.join("raw.bin"));
    // A free port: bound and released (the recorder binds it next).
    let port = UdpSocket::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    let listen = format!("127.0.0.1:{port}");
    let mut child = Command::new(env!("CARGO_BIN_EXE_gsens"))
        .args(["import", "gnss-sdr-monitor", "--listen", &listen, "--out", &s(&out), "--raw", &s(&raw)])
        .args(["--gnss-sdr-conf", &s(&fixture().join("gnss-sdr.conf")), "--idle-timeout-s", "3"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    err.read_line(&mut line).unwrap();
    assert!(line.starts_with("listening on"), "{line}");
    let bytes = std::fs::read(fixture().join("monitor.bin")).unwrap();
    let datagrams = split_capture(&bytes).unwrap();
    let tx = UdpSocket::bind("127.0.0.1:0").unwrap();
    let garbage: &[u8] = b"not protobuf \xff\xff";
    let mut sent: Vec<&[u8]> = Vec::new();
    for (k, dg) in datagrams.iter().enumerate().take(1200) {
        if k == 100 {
            tx.send_to(garbage, &listen).unwrap();
            sent.push(garbage);
        }
        tx.send_to(dg, &listen).unwrap();
        sent.push(dg);
        if k % 50 == 0 {
            std::thread::sleep(std::time::Duration::from_millis(2));
        }
    }
    let output = child.wait_with_output().unwrap();
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut err, &mut rest).unwrap();
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(output.status.success(), "{stdout}\n{rest}");
    // The raw file holds datagrams as received: those sent, in the order sent, each once at most.
    let raw = std::fs::read(&raw).unwrap();
    let received = split_capture(&raw).unwrap();
    let mut unsent = sent.iter();
    assert!(received.iter().all(|r| unsent.any(|s| s == r)), "the raw file holds a datagram not sent, or out of order");
    assert!(stdout.contains(&format!("received {} datagrams (", received.len())), "{stdout}");
    if received.contains(&garbage) {
        assert!(rest.contains("not a GNSS-SDR Observables message"), "{rest}");
    }
    let csv = std::fs::read_to_string(&out).unwrap();
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    assert!(!rows.is_empty(), "no rows\n{stdout}");
    for r in &rows {
        let t: f64 = r.split(',').next().unwrap().parse().unwrap();
        assert!((t / 0.02 - (t / 0.02).round()).abs() < 1e-6, "{r}");
    }
    // And `gsens estimate --tracking` would read it: the header is the format's.
    assert!(csv.starts_with("t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad\n"));
}

#[test]
fn nothing_received_is_an_error_naming_the_address() {
    let port = UdpSocket::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    let listen = format!("127.0.0.1:{port}");
    let d = temp_dir("monitor-cmd-none");
    let o = Command::new(env!("CARGO_BIN_EXE_gsens"))
        .args(["import", "gnss-sdr-monitor", "--listen", &listen, "--fs-hz", "2048000", "--idle-timeout-s", "0.3"])
        .args(["--out", &s(&d.join("t.csv"))])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains(&listen) && e.contains("TrackingMonitor.enable_monitor"), "{e}");
}
