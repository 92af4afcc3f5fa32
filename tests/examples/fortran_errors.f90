! The Fortran module's errors and arrays on 3 ranks (run by insitu_c_test.sh against the install):
! a status instead of a stop, the C API's message, an array the module cannot pass refused by the
! next frame on every rank alike (then the session renders again), real(8) and unsigned
! integer(2) voxels, the image on render rank 0 only, every style call, particles and meshes.
program fortran_errors
  use, intrinsic :: iso_c_binding, only: c_float, c_double, c_int8_t, c_int16_t, c_int32_t, &
                                          c_int64_t
  use mpi_f08
  use mpi, only: old_world => MPI_COMM_WORLD  ! the old `mpi` module's integer handle
  use dfbwall
  implicit none
  type(dfbwall_options) :: options
  type(dfbwall_style) :: style
  type(dfbwall_session) :: session
  type(dfbwall_brick) :: brick, never_made
  real(c_double), allocatable, target :: field(:, :, :)
  real(c_float), target :: centers(3, 2), flat(2, 2), radii(1), positions(3, 3)
  integer(c_int32_t), target :: triangles(3, 1)
  integer(c_int16_t), allocatable, target :: counts(:, :, :)
  integer(c_int8_t), pointer :: pixels(:, :, :)
  integer :: provided, rank, status, v, x, y, z, width, height, z0, z1

  call MPI_Init_thread(MPI_THREAD_MULTIPLE, provided)
  call MPI_Comm_rank(MPI_COMM_WORLD, rank)
  ! A session on the old module's handle, without options: an 800x600 canvas.
  call dfbwall_session_new(session, old_world, status=status)
  call expect(status == DFBWALL_OK .and. dfbwall_session_canvas_width(session) == 800 .and. &
              dfbwall_session_canvas_height(session) == 600, "a session on an mpi integer handle")
  call dfbwall_session_close(session)
  call dfbwall_session_release(session)
  call dfbwall_options_new(options)
  call dfbwall_options_set(options, "colour", "red", status)
  call expect(status == DFBWALL_ERROR_INPUT .and. &
              index(dfbwall_last_error(), "unknown option 'colour'") > 0, "an unknown option")
  call dfbwall_options_set(options, "width", "64")
  call dfbwall_options_set(options, "height", "48")
  call dfbwall_options_set(options, "tile-size", "16")
  call dfbwall_options_set(options, "threads", "1")
  call dfbwall_session_new(session, MPI_COMM_WORLD%MPI_VAL, options)
  call dfbwall_options_release(options)
  call dfbwall_session_render_frame(session, status)
  call expect(status == DFBWALL_ERROR_USAGE, "a frame before a style")

  call dfbwall_style_new(style)
  call dfbwall_style_add_volume(style, "f", [16, 16, 16], [0.0, 0.0, 0.0], [1.0, 1.0, 1.0], v)
  call dfbwall_style_set_transfer_function(style, 7, "inferno", 0.5, status)
  call expect(status == DFBWALL_ERROR_INPUT .and. index(dfbwall_last_error(), "volume 7") > 0, &
              "a volume not in the style")
  call dfbwall_style_set_seed(style, 3_c_int64_t)
  call dfbwall_style_set_particles(style, [0.9, 0.9, 0.2], 1.0)
  call dfbwall_style_set_mesh(style, [0.2, 0.8, 0.9], 1.0)
  call dfbwall_style_add_light(style, DFBWALL_LIGHT_DIRECTIONAL, [-1.0, -1.0, 1.0], &
                               [0.0, 0.0, 0.0], [1.0, 1.0, 1.0], 2.0)
  call dfbwall_style_add_light(style, DFBWALL_LIGHT_AMBIENT, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], &
                               [1.0, 1.0, 1.0], 0.3)
  call dfbwall_style_set_ambient_occlusion(style, 2, 4.0)
  call dfbwall_style_set_shadows(style, .true.)
  call dfbwall_style_set_sampling_rate(style, 1.0)
  call dfbwall_style_set_samples_per_pixel(style, 1)
  call dfbwall_style_set_background(style, [0.0, 0.0, 0.1])
  call dfbwall_style_set_volume_visible(style, v, .true.)
  call dfbwall_style_set_value_range(style, v, 0.0, 3.0)
  call dfbwall_session_set_style(session, style)
  call dfbwall_style_release(style)
  call dfbwall_session_set_camera(session, [30.0, 20.0, -30.0], [7.5, 7.5, 7.5], &
                                  [0.0, 1.0, 0.0], 40.0)
  allocate (field(0:15, 0:15, 0:15), counts(0:15, 0:15, 0:15))
  do z = 0, 15
    do y = 0, 15
      do x = 0, 15
        field(x, y, z) = sin(x/3d0) + cos(y/4d0) + z/16d0
        counts(x, y, z) = int(x*y*z, c_int16_t)
      end do
    end do
  end do

  ! Every other x: not contiguous. Refused by the next frame on all three ranks.
  call dfbwall_session_clear_bricks(session)
  if (rank == 0) then
    call dfbwall_brick_init(brick, 0, [0.0, 0.0, 0.0], [15.0, 15.0, 15.0])
    call dfbwall_brick_add_volume(brick, [0, 0, 0], field(::2, :, :))
    call dfbwall_session_add_brick(session, brick)
  end if
  call dfbwall_session_render_frame(session, status)
  call expect(status == DFBWALL_ERROR_INPUT .and. &
              index(dfbwall_last_error(), "brick 0: volume part 0: the array is not contiguous") &
              > 0, "a strided array refused on every rank")

  ! real(8), converted; the session renders again.
  call dfbwall_session_clear_bricks(session)
  if (rank == 0) then
    call dfbwall_brick_init(brick, 0, [0.0, 0.0, 0.0], [15.0, 15.0, 15.0])
    call dfbwall_brick_add_volume(brick, [0, 0, 0], field)
    call dfbwall_session_add_brick(session, brick)
  end if
  call dfbwall_session_render_frame(session, status)
  call expect(status == DFBWALL_OK, "a real(8) brick")
  call dfbwall_session_image(session, pixels, width, height)
  if (rank == 0) then
    call expect(associated(pixels) .and. width == 64 .and. height == 48, "the image on rank 0")
    call expect(all(shape(pixels) == [4, 64, 48]), "the image's shape")
    call expect(any(pixels(1, :, :) /= pixels(1, 1, 1)), "a picture, not a blank")
  else
    call expect(.not. associated(pixels) .and. width == 0, "no image elsewhere")
  end if

  ! Two bricks of unsigned integer(2), one on each of two ranks: z 0-7 and 7-15, sharing plane 7.
  call dfbwall_session_clear_bricks(session)
  if (rank < 2) then
    z0 = merge(0, 7, rank == 0)
    z1 = merge(8, 15, rank == 0)
    call dfbwall_brick_init(brick, rank, [0.0, 0.0, real(z0)], [15.0, 15.0, real(min(z1, 15))])
    call dfbwall_brick_add_volume(brick, [0, 0, z0], counts(:, :, z0:z1), unsigned=.true.)
    call dfbwall_session_add_brick(session, brick)
  end if
  call dfbwall_session_render_frame(session, status)
  call expect(status == DFBWALL_OK, "unsigned integer(2) bricks on two ranks")
  call expect(dfbwall_session_scene_bytes(session) > 0 .eqv. rank < 2, "scene bytes")

  ! Particles and a triangle on rank 2, which holds none of the volume; then centres given as
  ! 2 rows, refused on every rank.
  centers = reshape([4.0, 4.0, 4.0, 11.0, 11.0, 11.0], [3, 2])
  radii = 1.5
  positions = reshape([0.0, 0.0, 15.0, 15.0, 0.0, 15.0, 0.0, 15.0, 15.0], [3, 3])
  triangles = reshape([0, 1, 2], [3, 1])
  flat = 1
  call dfbwall_session_clear_bricks(session)
  if (rank == 2) then
    call dfbwall_brick_init(brick, 5, [0.0, 0.0, 0.0], [15.0, 15.0, 15.0])
    call dfbwall_brick_add_no_volume(brick)
    call dfbwall_brick_set_particles(brick, centers, radii)
    call dfbwall_brick_set_ghost_particles(brick, centers(:, 1:1), radii)
    call dfbwall_brick_set_mesh(brick, positions, triangles)
    call dfbwall_brick_set_ghost_mesh(brick, positions, triangles)
    call dfbwall_session_add_brick(session, brick)
  end if
  call dfbwall_session_render_frame(session, status)
  call expect(status == DFBWALL_OK, "particles and a mesh")
  call expect(dfbwall_session_scene_bytes(session) > 0 .eqv. rank == 2, "scene bytes of particles")
  call dfbwall_session_clear_bricks(session)
  if (rank == 2) then
    call dfbwall_brick_init(brick, 5, [0.0, 0.0, 0.0], [15.0, 15.0, 15.0])
    call dfbwall_brick_add_no_volume(brick)
    call dfbwall_brick_set_particles(brick, flat, radii)
    call dfbwall_session_add_brick(session, brick)
  end if
  call dfbwall_session_render_frame(session, status)
  call expect(status == DFBWALL_ERROR_INPUT .and. index(dfbwall_last_error(), &
              "brick 5: particle centers: the array has 2 rows, not 3") > 0, "centres as 2 rows")
  ! A brick never given to dfbwall_brick_init, on rank 1: refused on every rank.
  call dfbwall_session_clear_bricks(session)
  if (rank == 1) call dfbwall_session_add_brick(session, never_made)
  call dfbwall_session_render_frame(session, status)
  call expect(status == DFBWALL_ERROR_INPUT .and. index(dfbwall_last_error(), &
              "render rank 1 refused its input: a brick before dfbwall_brick_init") > 0, &
              "a brick never made")

  call dfbwall_session_close(session)
  call dfbwall_session_release(session)
  print '(a,i0,a)', "rank ", rank, ": the Fortran module's errors and arrays as they should be"
  call MPI_Finalize()

contains

  subroutine expect(condition, what)
    logical, intent(in) :: condition
    character(len=*), intent(in) :: what
    if (condition) return
    print '(a,i0,a,a,a,a)', "rank ", rank, ": FAIL: ", what, ": ", dfbwall_last_error()
    call MPI_Abort(MPI_COMM_WORLD, 1)
  end subroutine

end program fortran_errors
