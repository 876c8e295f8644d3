//! Unit tests of the result places: folders refused or replaced whole with --force, dropped claims, the working
//! directory and inputs kept safe, result files' folders.

use super::*;

fn files(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    v.sort();
    v
}

#[test]
fn a_folder_with_files_is_refused_without_force_and_replaced_whole_with_it() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("sim");
    std::fs::create_dir_all(out.join("train")).unwrap();
    std::fs::write(out.join("train/old.csv"), "old").unwrap();
    std::fs::write(out.join("truth.json"), "{}").unwrap();
    let e =
        crate::api::settings::as_flags(&OutDir::claim(&out, "--out", false, &Inputs::new()).unwrap_err().to_string());
    assert_eq!(
        e,
        format!(
            "--out {}: the folder already holds files (train, truth.json); give --force to replace it whole, or \
             another --out",
            out.display()
        )
    );
    let d = OutDir::claim(&out, "--out", true, &Inputs::new()).unwrap();
    std::fs::create_dir(d.path().join("train")).unwrap();
    std::fs::write(d.path().join("train/new.csv"), "new").unwrap();
    assert_eq!(d.shown(&d.path().join("train/new.csv")), out.join("train/new.csv"));
    // Before the commit the old folder is untouched.
    assert_eq!(files(&out.join("train")), ["old.csv"]);
    d.commit().unwrap();
    assert_eq!(files(&out), ["train"]);
    assert_eq!(files(&out.join("train")), ["new.csv"]);
    // Nothing left beside it: no staging folder, no old copy.
    assert_eq!(files(tmp.path()), ["sim"]);
}

#[test]
fn a_dropped_claim_leaves_the_old_folder_and_nothing_else() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("bags");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("a.mcap"), "old").unwrap();
    {
        let d = OutDir::claim(&out, "--mcap", true, &Inputs::new()).unwrap();
        std::fs::write(d.path().join("b.mcap"), "half").unwrap();
    }
    assert_eq!(files(tmp.path()), ["bags"]);
    assert_eq!(files(&out), ["a.mcap"]);
}

#[test]
fn new_and_empty_folders_need_no_force() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("deep/er/sim");
    let d = OutDir::claim(&out, "--out", false, &Inputs::new()).unwrap();
    std::fs::write(d.path().join("x"), "x").unwrap();
    d.commit().unwrap();
    assert_eq!(files(&out), ["x"]);
    let empty = tmp.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    let d = OutDir::claim(&empty, "--out", false, &Inputs::new()).unwrap();
    std::fs::write(d.path().join("y"), "y").unwrap();
    d.commit().unwrap();
    assert_eq!(files(&empty), ["y"]);
}

#[test]
fn force_never_replaces_a_folder_holding_the_working_directory() {
    let here = std::env::current_dir().unwrap();
    let parent = here.parent().unwrap();
    let e =
        crate::api::settings::as_flags(&OutDir::claim(parent, "--out", true, &Inputs::new()).unwrap_err().to_string());
    assert!(e.ends_with("--force will not replace a folder that holds the working directory"), "{e}");
}

#[test]
fn a_folder_that_holds_or_lies_inside_an_input_is_refused_even_with_force() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    std::fs::create_dir(&data).unwrap();
    std::fs::write(data.join("run.mcap"), "bag").unwrap();
    let inputs = Inputs::data(std::slice::from_ref(&data.join("run.mcap"))).with("--robot", data.join("r.toml"));
    for force in [false, true] {
        let e = crate::api::settings::as_flags(&OutDir::claim(&data, "--tum", force, &inputs).unwrap_err().to_string());
        assert_eq!(
            e,
            format!(
                "--tum {}: this folder holds the data {}, which this command reads; give --tum a folder apart \
                 from its inputs (--force never replaces an input)",
                data.display(),
                data.join("run.mcap").display()
            )
        );
    }
    // Inside the data's folder, through a `..` and a link: refused too, and nothing is created.
    let inputs = Inputs::data(std::slice::from_ref(&data));
    let inside = tmp.path().join("other/../data/exported");
    let e = crate::api::settings::as_flags(&OutDir::claim(&inside, "--mcap", true, &inputs).unwrap_err().to_string());
    assert!(e.contains(": this folder is inside the data "), "{e}");
    std::os::unix::fs::symlink(&data, tmp.path().join("link")).unwrap();
    let e = crate::api::settings::as_flags(
        &OutDir::claim(&tmp.path().join("link"), "--out", true, &inputs).unwrap_err().to_string(),
    );
    assert!(e.contains(": this folder holds the data "), "{e}");
    assert_eq!(files(&data), ["run.mcap"]);
    assert_eq!(files(tmp.path()), ["data", "link"]);
    // A sibling folder is fine.
    OutDir::claim(&tmp.path().join("tum"), "--tum", true, &inputs).unwrap().commit().unwrap();
}

#[test]
fn a_result_file_needs_an_existing_folder() {
    let tmp = tempfile::tempdir().unwrap();
    let missing = tmp.path().join("fitted/model.toml");
    assert_eq!(
        check_file(&missing, "--out").unwrap_err().to_string(),
        format!(
            "--out {}: the folder {} does not exist (create it first: mkdir -p {})",
            missing.display(),
            tmp.path().join("fitted").display(),
            tmp.path().join("fitted").display()
        )
    );
    assert_eq!(
        check_file(tmp.path(), "--out").unwrap_err().to_string(),
        format!("--out {}: this is a folder; give a file name in it", tmp.path().display())
    );
    check_file(&tmp.path().join("model.toml"), "--out").unwrap();
    assert!(files(tmp.path()).is_empty(), "the probe file is removed");
}
