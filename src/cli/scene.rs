//! `lanterna scene …`: generate test scenes (not yet implemented).

#[derive(clap::Subcommand)]
pub enum Command {
    /// Generate a scene (not yet implemented).
    Generate {},
}

pub fn run(_command: Command) -> anyhow::Result<()> {
    anyhow::bail!("`lanterna scene` is not implemented yet")
}
