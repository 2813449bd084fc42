from setuptools import find_packages, setup

package_name = 'hrc_bag'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test', 'bench']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/params',
         ['../../params/recorder.yaml', '../../params/replay.yaml']),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='hrc developers',
    maintainer_email='hrc@example.org',
    description='MCAP recorder, bag replay and the offline report of hrc sessions.',
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
            'recorder_node = hrc_bag.recorder_node:main',
            'replay_node = hrc_bag.replay_node:main',
        ],
    },
)
