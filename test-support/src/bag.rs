//! The shared ROS 1 benchmark bag, which `../shared/data` keeps zipped, unzipped once per test
//! process into the system's temporary folder; and its MCAP twin.

use std::path::PathBuf;

use crate::data::shared_data;

/// `general_tracking_moving_1.bag`, unzipped once into the system's temporary folder (beside
/// its zip's size, so a changed zip is unzipped again), or `None` when the data is absent.
pub fn moving_bag() -> Option<PathBuf> {
    static BAG: std::sync::OnceLock<Option<PathBuf>> = std::sync::OnceLock::new();
    BAG.get_or_init(unzip_moving_bag).clone()
}

fn unzip_moving_bag() -> Option<PathBuf> {
    let zip_path = shared_data("leg_tracker/general_tracking_moving_1.bag.zip")?;
    let size = std::fs::metadata(&zip_path).ok()?.len();
    let dir = std::env::temp_dir().join(format!("haunts-bag-tests-{size}"));
    let out = dir.join("general_tracking_moving_1.bag");
    if out.exists() {
        return Some(out);
    }
    std::fs::create_dir_all(&dir).unwrap();
    let mut archive = zip::ZipArchive::new(std::fs::File::open(&zip_path).unwrap()).unwrap();
    let mut member = archive.by_name("general_tracking_moving_1.bag").unwrap();
    // Written beside and renamed, so that test processes running at once never see half a file.
    let tmp = dir.join(format!("unzip-{}.tmp", std::process::id()));
    let mut file = std::fs::File::create(&tmp).unwrap();
    std::io::copy(&mut member, &mut file).unwrap();
    std::fs::rename(&tmp, &out).unwrap();
    Some(out)
}

/// The MCAP twin of the bag.
pub fn moving_mcap() -> Option<PathBuf> {
    shared_data("leg_tracker/general_tracking_moving_1.mcap")
}
